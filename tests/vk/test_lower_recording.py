"""The pure lowering (``rgraph.vk.lower.lower``): a plan and a queue-family layout -> the
Recording the runtime records, computed without Vulkan; workarounds switch off by name;
``rgraph inspect --lowered`` prints it."""

from __future__ import annotations

import subprocess
import sys

import pytest

from rgraph.cli import main
from rgraph.compiler.pipeline import compile_graph
from rgraph.vk.lower import LAYER_WORKAROUNDS, lower, separate_families, single_family
from rgraph.vk.lower.barriers import REWRITES

SINGLE, SEPARATE = single_family(), separate_families()


@pytest.fixture(scope="module")
def surgery() -> dict:
    return compile_graph("surgery", size=(64, 64), profile="lavapipe")


def _transfer_plan() -> dict:
    sys.path.insert(0, str(__import__("locations").TESTS))
    from vkplans import PlanBuilder

    b = PlanBuilder((32, 32))
    b.image("src", "R8G8B8A8_UNORM").image("dst", "R8G8B8A8_UNORM", lifetime="output")
    b.add_pass("produce", "compute", [("src", "storage_write")])
    b.add_pass("copy", "transfer", [("src", "transfer_src"), ("dst", "transfer_dst")])
    return b.build()


def _specs(rec, role="before"):
    return [(p.name, s) for p in rec.passes for call in getattr(p, role) for s in call]


@pytest.mark.parametrize("queues", [SINGLE, SEPARATE], ids=["single", "separate"])
def test_recording_covers_every_pass_once_in_a_valid_order(surgery, queues):
    rec = lower(surgery, queues)
    assert [p.name for p in rec.passes] == [p["name"] for p in surgery["passes"]]
    assert [i for b in rec.batches for i in b.passes] == list(range(len(surgery["passes"])))
    assert sorted(rec.order) == list(range(len(rec.batches)))
    for batch in rec.batches:  # a batch is one VkQueue
        assert len({queues.family(surgery["passes"][i]["queue"]) for i in batch.passes}) == 1
    assert rec.workarounds == LAYER_WORKAROUNDS


def test_single_family_records_no_ownership_transfer_and_no_semaphore(surgery):
    rec = lower(surgery, SINGLE)
    assert all(s.src_family is None and s.dst_family is None for _n, s in _specs(rec) + _specs(rec, "after"))
    assert rec.edges == () and len(rec.batches) >= 1


def test_separate_families_record_release_acquire_pairs_and_semaphores(surgery):
    rec = lower(surgery, SEPARATE)
    releases = [s for _n, s in _specs(rec, "after") if s.src_family is not None]
    acquires = [s for _n, s in _specs(rec) if s.dst_family is not None]
    assert releases and acquires
    assert {(s.resource, s.src_family, s.dst_family) for s in releases} <= \
        {(s.resource, s.src_family, s.dst_family) for s in acquires} | {(s.resource, s.src_family, s.dst_family)
                                                                        for calls in rec.first_frame.values()
                                                                        for call in calls for s in call}
    assert any(not e.frame_edge for e in rec.edges) and any(e.frame_edge for e in rec.edges)
    for e in rec.edges:
        if not e.frame_edge:
            assert rec.order.index(e.signal_batch) < rec.order.index(e.wait_batch)


def test_compiler_names_copy_and_the_transfer_workaround_widens_it():
    """The usage table has its true stage (COPY); the layer-1.3.239 rewrite records ALL_TRANSFER."""
    plan = compile_graph("surgery", size=(64, 64), profile="lavapipe")
    assert not any("ALL_TRANSFER" in a["stages"] for p in plan["passes"] for a in p["accesses"])
    plan = _transfer_plan()
    copy_stages = {s for p in plan["passes"] for b in p["barriers"] for s in b["dst"]["stages"]}
    assert "COPY" in copy_stages
    on = lower(plan, SINGLE)
    off = lower(plan, SINGLE, workarounds=())
    on_stages = {st for _n, s in _specs(on) for st in s.dst_stages}
    off_stages = {st for _n, s in _specs(off) for st in s.dst_stages}
    assert "ALL_TRANSFER" in on_stages and "COPY" not in on_stages
    assert "COPY" in off_stages and "ALL_TRANSFER" not in off_stages
    assert plan["passes"][1]["barriers"][0]["dst"]["stages"] == ["COPY"]  # the input plan is not changed


def test_switching_workarounds_off_drops_exactly_their_rewrites(surgery):
    on = {(n, s.resource): s for n, s in _specs(lower(surgery, SINGLE))}
    off = {(n, s.resource): s for n, s in _specs(lower(surgery, SINGLE, workarounds=()))}
    assert on.keys() == off.keys()
    # transitions after reads: the layer needs the reads (and the write they read) named
    named = [k for k in on if off[k].src_stages and off[k].src_access == () and off[k].old_layout != off[k].new_layout]
    assert named and all("MEMORY_READ" in on[k].src_access for k in named)
    only_name_read_write = lower(surgery, SINGLE, workarounds=("name_read_write",))
    assert only_name_read_write.workarounds == ("name_read_write",)
    changed = [k for k in on if on[k] != off[k]]
    assert changed and all(set(on[k].src_stages) >= set(off[k].src_stages) for k in changed)  # only widened


def test_rewrites_are_named_and_ordered():
    names = [r.name for r in REWRITES]
    assert names == ["chain_to_waits", "name_read_write", "fit_to_queue_family", "memory_read_after_reads",
                     "packed_range_global_barrier"]
    assert {r.name for r in REWRITES if r.layer} <= set(LAYER_WORKAROUNDS)
    with pytest.raises(ValueError, match="unknown layer workaround"):
        lower(_transfer_plan(), SINGLE, workarounds=("no_such_rewrite",))


def test_lowering_needs_no_vulkan(tmp_path):
    """Lowering and ``inspect --lowered`` import no Vulkan binding and open no device."""
    code = ("import sys; from rgraph.compiler.pipeline import compile_graph; from rgraph.vk.lower import lower, "
            "separate_families; from rgraph.vk.lower.text import format_recording; "
            "rec = lower(compile_graph('surgery', size=(64, 64), profile='lavapipe'), separate_families()); "
            "format_recording(rec); assert 'vulkan' not in sys.modules, 'vulkan imported'; print('ok')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr


def test_inspect_lowered_prints_every_pass_and_batch(tmp_path, capsys, surgery):
    import json

    path = tmp_path / "plan.json"
    path.write_text(json.dumps(surgery))
    assert main(["inspect", str(path), "--lowered", "--queues", "separate"]) == 0
    out = capsys.readouterr().out
    for p in surgery["passes"]:
        assert f" {p['name']}  [{p['queue']}, family " in out
    assert "queues: model: separate graphics, compute and transfer families" in out
    assert "semaphore: batch" in out and "family 0 -> 1" in out
    assert main(["inspect", str(path), "--lowered", "--no-layer-workarounds"]) == 0
    assert "layer workarounds: none" in capsys.readouterr().out


def test_typed_plan_lowers_like_its_document():
    import rgraph

    compiled = rgraph.compile("surgery", size=(64, 64), profile="lavapipe")
    typed, document = lower(compiled.plan, SEPARATE), lower(compiled.as_dict(), SEPARATE)
    assert (typed.passes, typed.batches, typed.edges, typed.order) == \
        (document.passes, document.batches, document.edges, document.order)


@pytest.mark.parametrize(("seed", "passes"), [(10, 10), (1, 15), (20, 20)])
def test_true_transfer_stages_record_as_the_old_all_transfer_plans(seed, passes):
    """With the workarounds on, a plan naming COPY (the compiler's usage table now) records
    exactly what the same plan naming ALL_TRANSFER (the table before) recorded."""
    import json
    import tempfile
    from pathlib import Path

    from rgraph.random_graph import random_graph, to_yaml

    path = Path(tempfile.mkdtemp()) / f"g{seed}.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    plan = compile_graph(str(path), size=(16, 16), policy="aliased")
    text = json.dumps(plan)
    assert '"COPY"' in text, "the seed should have a transfer usage"
    old = json.loads(text.replace('"COPY"', '"ALL_TRANSFER"'))
    for queues in (SINGLE, SEPARATE):
        new_rec, old_rec = lower(plan, queues), lower(old, queues)
        assert (new_rec.passes, new_rec.edges, new_rec.order, new_rec.first_frame) == \
            (old_rec.passes, old_rec.edges, old_rec.order, old_rec.first_frame)


def test_inspect_lowered_refuses_a_partial_plan_with_one_line(tmp_path, capsys, surgery):
    import json

    broken = json.loads(json.dumps(surgery))
    del broken["passes"][2]["barriers"]
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(broken))
    assert main(["inspect", str(path), "--lowered"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "malformed plan: passes[2]: missing key 'barriers'" in err[0], err
