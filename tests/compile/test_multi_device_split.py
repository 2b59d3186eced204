"""The multi-device transformation (pure): where the composite goes, bands, copies, waits, and
what ``rgraph check`` says about cross-device ordering."""

from __future__ import annotations

import copy

import pytest
from locations import ROOT

from rgraph.check import check_plan
from rgraph.compiler.multi_device import Split, bands
from rgraph.compiler.pipeline import compile_graph_plan
from rgraph.errors import RGraphError
from rgraph.plan import dump, load, to_json_dict
from rgraph.plan.devices import project
from rgraph.vk.multi.shares import share_of

PROBE_GRAPH = ROOT / "tests" / "multi_graphs" / "probe_split.yaml"


def _plan(graph, mode, devices=2):
    return compile_graph_plan(graph, size=(64, 64), split=Split(devices, mode))


@pytest.mark.parametrize("height,devices", [(64, 2), (65, 3), (7, 4), (1080, 2)])
def test_bands_cover_the_screen_top_to_bottom(height, devices):
    out = bands(height, Split(devices, "sort-first"))
    assert out[0][0] == 0 and sum(r for _y, r in out) == height
    assert all(a[0] + a[1] == b[0] for a, b in zip(out, out[1:], strict=False))
    assert max(r for _y, r in out) - min(r for _y, r in out) <= 1


def test_weighted_bands_follow_the_weights():
    assert bands(100, Split(2, "sort-first", "dynamic", (3.0, 1.0))) == [(0, 75), (75, 25)]


def test_surgery_sort_first_composites_before_the_first_neighbourhood_read():
    plan = _plan("surgery", "sort-first")
    info = plan.multi_device
    assert info["cut"] == "hbao_downsample" and list(info["crossing"]) == ["depth"]
    by_name = {p.name: p for p in plan.passes}
    assert list(by_name["depth_prepass"].params["rgraph.scissor"]) == [0, 0, 64, 32]
    assert list(by_name["depth_prepass@1"].params["rgraph.scissor"]) == [0, 32, 64, 32]
    # after the composite everything is on device 0; blurs, AO, SSS and bloom included
    for name in ("hbao", "sss_blur_h", "bloom_blur_v", "tonemap"):
        assert by_name[name].device == 0
    assert not any(p.name.startswith(("hbao", "sss", "bloom")) for p in plan.passes if p.device == 1)
    # every resource belongs to the device of the passes using it
    owner = {r.name: r.device for r in plan.resources}
    assert all(owner[a.resource] == p.device for p in plan.passes for a in p.accesses)


def test_copy_waits_on_the_sending_device_and_check_is_clean():
    plan = _plan(PROBE_GRAPH, "sort-first")
    uploads = [p for p in plan.passes if "copy_from" in p.params]
    assert {p.name for p in uploads} == {"albedo.upload1", "lit.upload1"}
    for p in uploads:
        sender = next(q for q in plan.passes if q.name == p.params["copy_from"]["pass"])
        assert sender.device == 1 and sender.index < p.index
        assert any(w.device == 1 and w.value == sender.signals[-1].value for w in p.waits)
    assert check_plan(to_json_dict(plan)) == []


def test_check_finds_a_missing_cross_device_wait_and_a_foreign_access():
    doc = to_json_dict(_plan(PROBE_GRAPH, "sort-last"))
    no_wait = copy.deepcopy(doc)
    for p in no_wait["passes"]:
        if p["name"] == "lit.upload1":
            p["waits"] = [w for w in p["waits"] if w.get("device") is None]
    assert [h.pass_name for h in check_plan(no_wait)] == ["lit.upload1"]
    foreign = copy.deepcopy(doc)
    blur = next(p for p in foreign["passes"] if p["name"] == "blur")
    blur["accesses"][0]["resource"] = "lit@1"
    assert any("of device 1" in h.message for h in check_plan(foreign))


@pytest.mark.parametrize("mode", ["sort-first", "sort-last"])
def test_plans_round_trip_and_project_per_device(mode):
    plan = _plan(PROBE_GRAPH, mode, devices=3)
    assert load(dump(plan)) == plan
    for d in range(3):
        sub = project(plan, d)
        assert all(p.device == 0 and not any(w.device is not None for w in p.waits) for p in sub.passes)
        assert [p.index for p in sub.passes] == list(range(len(sub.passes)))
        assert len(sub.passes) == sum(1 for p in plan.passes if p.device == d)
    assert project(plan, 1).outputs == ("albedo.tile", "lit.tile") if mode == "sort-first" else True


def test_one_device_plans_are_unchanged_by_the_new_keys():
    text = dump(compile_graph_plan("surgery", size=(64, 64)))
    assert '"device": 1' not in text and "multi_device" not in text
    assert compile_graph_plan("surgery", size=(64, 64), split=Split(1, "sort-first")) == \
        compile_graph_plan("surgery", size=(64, 64))


def test_sort_last_without_a_split_depth_is_refused(tmp_path):
    g = tmp_path / "g.yaml"
    g.write_text("rgraph: 1\nname: g\nresources:\n  a: {kind: image, format: r8g8b8a8_unorm, size: output}\n"
                 "  c: {kind: image, format: r8g8b8a8_unorm, size: output, lifetime: output}\npasses:\n"
                 "  draw: {kind: raster, writes: {a: color_attachment}}\n"
                 "  post: {kind: compute, reads: {a: sampled}, writes: {c: storage_write}}\noutputs: [c]\n")
    plan = _plan(g, "sort-last")  # no depth: nothing is draw-split, all on device 0
    assert {p.device for p in plan.passes} == {0}


class _Call:
    def __init__(self, n):
        self.index_count, self.instances = 3 * n, 1


def test_draw_shares_partition_the_calls_by_triangles():
    calls = [_Call(n) for n in (100, 10, 60, 50, 5)]
    shares = [share_of(calls, d, 2) for d in range(2)]
    assert sorted(id(c) for s in shares for c in s) == sorted(id(c) for c in calls)
    tri = [sum(c.index_count // 3 for c in s) for s in shares]
    assert abs(tri[0] - tri[1]) <= 100


def test_bad_split_arguments_are_one_line_errors():
    with pytest.raises(RGraphError):
        Split(2, "sort-middle")
    with pytest.raises(RGraphError):
        Split(0, "sort-first")
