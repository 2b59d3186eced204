"""Plan barriers -> barrier calls (``rgraph.vk.lower.barriers.lower_barriers``), pure: a fake device
with a separate compute queue family (as on NVIDIA) checks the exact structs of ownership
transfers, which lavapipe (one queue family) never records."""

from __future__ import annotations

import pytest

from rgraph.compiler.pipeline import compile_graph
from rgraph.random_graph import random_graph, to_yaml
from rgraph.stages import fit_to_queue, queue_supports
from rgraph.vk.lower.barriers import lower_barriers
from rgraph.vk.lower.model import BarrierSpec

TWO_FAMILIES = {"graphics": 0, "compute": 1, "transfer": 2}
ONE_FAMILY = {"graphics": 0, "compute": 0, "transfer": 0}
WHOLE = {"mips": [0, 1], "layers": [0, 1]}


@pytest.fixture(scope="module")
def surgery() -> dict:
    return compile_graph("surgery", size=(64, 64))


def _pass(plan: dict, name: str) -> dict:
    return next(p for p in plan["passes"] if p["name"] == name)


def _only(specs: list[BarrierSpec], resource: str) -> BarrierSpec:
    found = [s for s in specs if s.resource == resource]
    assert len(found) == 1, found
    return found[0]


def test_depth_to_compute_release_and_acquire_carry_no_layout_change(surgery):
    release = lower_barriers(_pass(surgery, "depth_prepass")["releases"], "release", TWO_FAMILIES)
    assert len(release) == 1  # one vkCmdPipelineBarrier2 after depth_prepass
    assert _only(release[0], "depth") == BarrierSpec(
        "depth", WHOLE, ("EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"), ("DEPTH_STENCIL_ATTACHMENT_WRITE",),
        (), (), "DEPTH_ATTACHMENT_OPTIMAL", "DEPTH_ATTACHMENT_OPTIMAL", 0, 1, "DEPTH_READ_ONLY_OPTIMAL")
    acquire, transition = lower_barriers(_pass(surgery, "hbao_downsample")["barriers"], "barrier", TWO_FAMILIES)
    # the acquire: chained to the semaphore wait (src stages = the wait's stages), no src access
    assert _pass(surgery, "hbao_downsample")["waits"][0]["stages"] == ["COMPUTE_SHADER"]
    assert _only(acquire, "depth") == BarrierSpec(
        "depth", WHOLE, ("COMPUTE_SHADER",), (), ("COMPUTE_SHADER",), ("SHADER_SAMPLED_READ",),
        "DEPTH_ATTACHMENT_OPTIMAL", "DEPTH_ATTACHMENT_OPTIMAL", 0, 1, "DEPTH_READ_ONLY_OPTIMAL")
    # then the layout change, an ordinary barrier on the compute queue chained to the acquire
    assert transition == [BarrierSpec(
        "depth", WHOLE, ("COMPUTE_SHADER",), ("MEMORY_READ",), ("COMPUTE_SHADER",), ("SHADER_SAMPLED_READ",),
        "DEPTH_ATTACHMENT_OPTIMAL", "DEPTH_READ_ONLY_OPTIMAL", None, None, "DEPTH_READ_ONLY_OPTIMAL")]


def test_ao_back_to_graphics(surgery):
    forward = _pass(surgery, "forward")
    release = lower_barriers(_pass(surgery, "hbao_upsample")["releases"], "release", TWO_FAMILIES)
    assert [(s.resource, s.old_layout, s.new_layout, s.src_family, s.dst_family, s.dst_stages, s.dst_access)
            for s in release[0]] == [
        ("ao", "GENERAL", "GENERAL", 1, 0, (), ()),
        ("depth", "DEPTH_READ_ONLY_OPTIMAL", "DEPTH_READ_ONLY_OPTIMAL", 1, 0, (), ()),
    ]
    groups = lower_barriers(forward["barriers"], "barrier", TWO_FAMILIES)
    assert len(groups) == 2
    wait_stages = {s for w in forward["waits"] for s in w["stages"]}
    ao = _only(groups[0], "ao")
    assert (ao.src_family, ao.dst_family, ao.old_layout, ao.new_layout, ao.src_access) == (1, 0, "GENERAL", "GENERAL", ())
    assert ao.src_stages == ao.dst_stages == ("FRAGMENT_SHADER",)
    assert set(ao.src_stages) <= wait_stages
    # depth keeps its layout across the transfer: no second barrier for it
    assert [(s.resource, s.old_layout, s.new_layout, s.src_family, s.src_stages, s.src_access) for s in groups[1]] == [
        ("ao", "GENERAL", "SHADER_READ_ONLY_OPTIMAL", None, ("FRAGMENT_SHADER",), ("MEMORY_READ",))]


def test_one_family_merges_each_pair_into_one_barrier_at_the_acquire(surgery):
    assert lower_barriers(_pass(surgery, "depth_prepass")["releases"], "release", ONE_FAMILY) == []
    (group,) = lower_barriers(_pass(surgery, "hbao_downsample")["barriers"], "barrier", ONE_FAMILY)
    plan_barrier = next(b for b in _pass(surgery, "hbao_downsample")["barriers"] if b["resource"] == "depth")
    assert _only(group, "depth") == BarrierSpec(
        "depth", WHOLE, tuple(plan_barrier["src"]["stages"]), tuple(plan_barrier["src"]["access"]),
        tuple(plan_barrier["dst"]["stages"]), tuple(plan_barrier["dst"]["access"]),
        "DEPTH_ATTACHMENT_OPTIMAL", "DEPTH_READ_ONLY_OPTIMAL", None, None, "DEPTH_READ_ONLY_OPTIMAL")


@pytest.mark.parametrize("seed", range(40))
def test_every_acquire_chains_to_its_semaphore_wait(tmp_path, seed):
    """On two families, in random graphs with async compute and transfer queues: releases keep
    their layout and have no dst scope; every acquire keeps the layout, has no src access, and
    its src stages meet the pass's wait on the releasing queue (or, for an acquire whose
    release ran in the previous frame, the runtime's frame-start wait covers all commands);
    a layout change follows as an ordinary barrier in the next call, chained to the acquire."""
    from rgraph.compiler.pipeline import compile_spec, frontend

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed, 14)))
    plan = compile_spec(frontend(path, size=(16, 16)).spec, policy="aliased")
    transfers = 0
    for p in plan["passes"]:
        for spec in (s for group in lower_barriers(p["releases"], "release", TWO_FAMILIES) for s in group):
            assert spec.src_family != spec.dst_family
            assert spec.old_layout == spec.new_layout and (spec.dst_stages, spec.dst_access) == ((), ())
        groups = lower_barriers(p["barriers"], "barrier", TWO_FAMILIES)
        acquires = [s for s in groups[0] if s.src_family is not None] if groups else []
        transitions = groups[1] if len(groups) > 1 else []
        for spec in acquires:
            transfers += 1
            assert spec.old_layout == spec.new_layout and spec.src_access == ()
            src_queue = next(q for q, f in TWO_FAMILIES.items() if f == spec.src_family)
            waits = {s for w in p["waits"] if w["queue"] == src_queue for s in w["stages"]}
            if waits:
                assert set(spec.src_stages) & waits, (p["name"], spec)
        for spec in transitions:
            acquire = next(a for a in acquires if a.resource == spec.resource and a.subresource == spec.subresource)
            assert spec.src_stages == acquire.dst_stages and spec.old_layout == acquire.new_layout
            assert spec.src_access == ("MEMORY_READ",)
            assert (spec.src_family, spec.dst_family) == (None, None)
    if seed == 0:
        assert transfers, "seed 0 should exercise at least one ownership transfer"


def test_transition_after_reads_names_memory_read():
    """A transition whose plan src is reads only (stages, no access) records srcAccessMask
    MEMORY_READ (a no-op by the spec; the form the 1.3.239 layer credits across command
    buffers); transitions after writes and from UNDEFINED keep the plan's src access."""
    def barrier(src_stages, src_access, old, new):
        return {"resource": "a", "subresource": WHOLE, "aliases": None,
                "src": {"stages": src_stages, "access": src_access, "layout": old, "queue": "graphics"},
                "dst": {"stages": ["COMPUTE_SHADER"], "access": ["SHADER_SAMPLED_READ"], "layout": new,
                        "queue": "graphics"}}
    after_reads, alias_after_reads, after_write, first_use, same_layout = (
        lower_barriers([b], "barrier", TWO_FAMILIES)[0][0] for b in (
            barrier(["COMPUTE_SHADER"], [], "GENERAL", "SHADER_READ_ONLY_OPTIMAL"),
            barrier(["COMPUTE_SHADER"], [], "UNDEFINED", "GENERAL"),  # aliased memory after its reads
            barrier(["COMPUTE_SHADER"], ["SHADER_STORAGE_WRITE"], "GENERAL", "SHADER_READ_ONLY_OPTIMAL"),
            barrier([], [], "UNDEFINED", "GENERAL"),
            barrier(["COMPUTE_SHADER"], [], "GENERAL", "GENERAL")))
    assert after_reads.src_access == alias_after_reads.src_access == ("MEMORY_READ",)
    assert after_write.src_access == ("SHADER_STORAGE_WRITE",)
    assert first_use.src_access == () and same_layout.src_access == ()


def test_barriers_of_a_pass_with_a_cross_queue_wait_chain_to_it():
    """An ordinary barrier whose src stages belong to another queue's work (an aliased
    resource's previous occupant, read on the compute queue) adds the wait's stages to its src
    stages, so it is ordered after the semaphore wait; acquires and first uses are unchanged."""
    alias = {"resource": "a", "subresource": WHOLE, "aliases": "old",
             "src": {"stages": ["COMPUTE_SHADER"], "access": [], "layout": "UNDEFINED", "queue": "graphics"},
             "dst": {"stages": ["COLOR_ATTACHMENT_OUTPUT"], "access": ["COLOR_ATTACHMENT_WRITE"],
                     "layout": "COLOR_ATTACHMENT_OPTIMAL", "queue": "graphics"}}
    first_use = {**alias, "resource": "b", "aliases": None, "src": {**alias["src"], "stages": []}}
    wait = ["COLOR_ATTACHMENT_OUTPUT", "FRAGMENT_SHADER"]
    (group,) = lower_barriers([alias, first_use], "barrier", TWO_FAMILIES, wait)
    assert _only(group, "a").src_stages == ("COLOR_ATTACHMENT_OUTPUT", "COMPUTE_SHADER", "FRAGMENT_SHADER")
    assert _only(group, "b").src_stages == ()
    (unchained,) = lower_barriers([alias], "barrier", TWO_FAMILIES)
    assert unchained[0].src_stages == ("COMPUTE_SHADER",)


def _random_plan(seed: int, passes: int, policy: str) -> dict:
    import tempfile
    from pathlib import Path

    path = Path(tempfile.mkdtemp()) / f"g{seed}.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    return compile_graph(str(path), size=(16, 16), policy=policy)


NVIDIA_FAMILIES = {"graphics": 0, "compute": 2, "transfer": 1}
CAPS = {"graphics": frozenset({"graphics", "compute", "transfer"}), "compute": frozenset({"compute", "transfer"}),
        "transfer": frozenset({"transfer"})}


@pytest.mark.parametrize("seed,passes,policy", [(0, 14, "dedicated"), (48, 16, "aliased"), (3, 20, "dedicated"),
                                                (11, 18, "aliased")])
def test_every_acquire_has_a_release_of_the_same_range(seed, passes, policy):
    """The layer pairs ownership transfers by exact subresource range: a resource released in
    two pieces (two passes) must be acquired in the same two pieces (H100 fuzz seed 0/14:
    'no matching release barrier queued for execution')."""
    plan = _random_plan(seed, passes, policy)
    releases, acquires = [], []
    for p in plan["passes"]:
        for role, key, out in (("release", "releases", releases), ("barrier", "barriers", acquires)):
            for group in lower_barriers(p[key], role, NVIDIA_FAMILIES):
                out += [(s.resource, str(s.subresource), s.src_family, s.dst_family) for s in group
                        if s.src_family is not None and s.src_family != s.dst_family]
    assert sorted(acquires) == sorted(releases)


def test_barriers_fit_the_recording_queue_family():
    """Seed 48's release of buf4 on the compute queue names the graphics reads before it
    (INDEX_INPUT): recorded on a compute-only family those stages are dropped."""
    plan = _random_plan(48, 16, "aliased")
    p = _pass(plan, "p00006")
    assert p["queue"] == "compute"
    plain = [s for g in lower_barriers(p["releases"], "release", NVIDIA_FAMILIES) for s in g if s.resource == "buf4"]
    assert "INDEX_INPUT" in plain[0].src_stages
    fitted = [s for g in lower_barriers(p["releases"], "release", NVIDIA_FAMILIES, (), CAPS["compute"])
              for s in g if s.resource == "buf4"]
    assert fitted[0].src_stages == ("COMPUTE_SHADER", "DRAW_INDIRECT")
    for q in plan["passes"]:
        for role, key in (("release", "releases"), ("barrier", "barriers")):
            for g in lower_barriers(q[key], role, NVIDIA_FAMILIES, (), CAPS[q["queue"]]):
                for s in g:
                    for stage in s.src_stages + s.dst_stages:
                        assert queue_supports(stage, CAPS[q["queue"]]), (q["name"], s)


def test_fit_to_queue_drops_accesses_of_dropped_stages():
    assert fit_to_queue(("FRAGMENT_SHADER", "COMPUTE_SHADER"), ("SHADER_SAMPLED_READ", "COLOR_ATTACHMENT_READ"),
                        CAPS["compute"]) == (("COMPUTE_SHADER",), ("SHADER_SAMPLED_READ",))
    assert fit_to_queue(("FRAGMENT_SHADER",), ("SHADER_SAMPLED_READ",), CAPS["compute"]) == ((), ())
    assert fit_to_queue(("COPY", "COMPUTE_SHADER"), ("TRANSFER_WRITE", "SHADER_STORAGE_WRITE"), CAPS["transfer"]) == \
        (("COPY",), ("TRANSFER_WRITE",))
    assert fit_to_queue(("ALL_COMMANDS",), ("MEMORY_WRITE",), CAPS["transfer"]) == (("ALL_COMMANDS",), ("MEMORY_WRITE",))


@pytest.mark.parametrize("seed,passes,policy,expected", [
    (13, 12, "dedicated", {"graphics": [("img2", "compute")]}),
    (48, 16, "aliased", {"compute": [("depth7", "graphics")]}),
])
def test_first_frame_releases_are_the_wrap_around_handoffs(seed, passes, policy, expected):
    """Frame 0's first-use acquires of persistent resources pair with releases from a previous
    frame that does not exist (H100 fuzz seeds 13/12 and 48/16): the runtime records exactly
    the releases whose acquire comes at or before them in the frame, once, after init."""
    from rgraph.vk.lower.batches import first_frame_releases
    from rgraph.vk.resources import SHARED

    plan = _random_plan(seed, passes, policy)
    shared = {r["name"] for r in plan["resources"] if r["lifetime"] in SHARED}
    got = first_frame_releases(plan, shared)
    assert {q: [(b["resource"], b["dst"]["queue"]) for b in bs] for q, bs in got.items()} == expected


def _access(resource, stages, write, layers=(0, 1)):
    return {"resource": resource, "subresource": {"mips": [0, 1], "layers": list(layers)}, "stages": stages,
            "write": write}


def _barrier(resource, src_stages, src_access, old, new, layers=(0, 1)):
    return {"resource": resource, "subresource": {"mips": [0, 1], "layers": list(layers)}, "aliases": None,
            "src": {"stages": src_stages, "access": src_access, "layout": old, "queue": "graphics"},
            "dst": {"stages": ["FRAGMENT_SHADER"], "access": ["SHADER_SAMPLED_READ"], "layout": new,
                    "queue": "graphics"}}


def _buffer_access(stages, write):
    return {"resource": "buf", "subresource": None, "stages": stages, "write": write}


def _buffer_barrier(src_stages, src_access, queue="graphics"):
    """A barrier on "buf" before a compute storage write."""
    return {"resource": "buf", "subresource": None, "aliases": None,
            "src": {"stages": src_stages, "access": src_access, "layout": None, "queue": queue},
            "dst": {"stages": ["COMPUTE_SHADER"], "access": ["SHADER_STORAGE_WRITE"], "layout": None,
                    "queue": "graphics"}}


def test_transition_after_reads_of_a_write_names_that_write():
    """Random graph seed 2936/17 on the H100: write (compute) -> barrier -> reads (compute) ->
    a semaphore wait -> transition. The transition names the write's stages and MEMORY_WRITE;
    a post-write barrier that lost its src access (a mutation) is not repaired; another
    layer's reads do not count."""
    from rgraph.vk.lower.workarounds.after_reads import writers_before_reads

    plan = {"passes": [
        {"accesses": [_access("a", ["COMPUTE_SHADER"], True)], "barriers": []},
        {"accesses": [_access("a", ["COMPUTE_SHADER"], False)],
         "barriers": [_barrier("a", ["COMPUTE_SHADER"], ["SHADER_STORAGE_WRITE"], "GENERAL", "GENERAL")]},
        {"accesses": [_access("a", ["FRAGMENT_SHADER"], False), _access("b", ["FRAGMENT_SHADER"], False)],
         "barriers": [_barrier("a", ["COMPUTE_SHADER"], [], "GENERAL", "SHADER_READ_ONLY_OPTIMAL"),
                      _barrier("b", ["COMPUTE_SHADER"], [], "GENERAL", "SHADER_READ_ONLY_OPTIMAL")]},
        {"accesses": [_access("b", ["COMPUTE_SHADER"], True, (1, 2))], "barriers": []},
    ]}
    writers = writers_before_reads(plan)
    assert writers[2] == {0: ("COMPUTE_SHADER",)}  # b's only write is to another layer
    (group,) = lower_barriers(plan["passes"][2]["barriers"], "barrier", TWO_FAMILIES, writers=writers[2])
    assert [(s.resource, s.src_stages, s.src_access) for s in group] == [
        ("a", ("COMPUTE_SHADER",), ("MEMORY_READ", "MEMORY_WRITE")), ("b", ("COMPUTE_SHADER",), ("MEMORY_READ",))]
    mutated = {"passes": [plan["passes"][0], {**plan["passes"][1], "barriers": [
        _barrier("a", ["COMPUTE_SHADER"], [], "GENERAL", "SHADER_READ_ONLY_OPTIMAL")]}]}
    assert writers_before_reads(mutated)[1] == {}


def test_transition_whose_src_access_the_family_cannot_perform_still_names_memory_read():
    """H100 fuzz seed 111329/13 (aliased): img1's first use on a compute family, placed over
    img3 that graphics wrote as a color attachment. Fitted to the compute family the src scope
    keeps only the semaphore wait's stage and no access; the transition gets MEMORY_READ."""
    barrier = _barrier("img1", ["COLOR_ATTACHMENT_OUTPUT"], ["COLOR_ATTACHMENT_WRITE"], "UNDEFINED", "GENERAL")
    barrier["dst"] = {"stages": ["COMPUTE_SHADER"], "access": ["SHADER_STORAGE_WRITE"], "layout": "GENERAL",
                      "queue": "compute"}
    barrier["src"]["queue"] = "compute"
    (group,) = lower_barriers([barrier], "barrier", TWO_FAMILIES, ["COMPUTE_SHADER"], frozenset({"compute"}))
    assert [(s.src_stages, s.src_access) for s in group] == [(("COMPUTE_SHADER",), ("MEMORY_READ",))]


def test_buffer_barrier_before_a_write_after_reads_names_the_earlier_write():
    """H100 fuzz seed 1/22: a persistent buffer written by compute, read as indirect and
    uniform, then written again; the write-after-read barrier (execution only in the plan)
    names the earlier write's stages and MEMORY_WRITE."""
    from rgraph.vk.lower.workarounds.after_reads import writers_before_reads

    plan = {"passes": [
        {"accesses": [_buffer_access(["DRAW_INDIRECT"], False)],
         "barriers": [_buffer_barrier(["COMPUTE_SHADER"], ["SHADER_STORAGE_WRITE"])]},
        {"accesses": [_buffer_access(["COMPUTE_SHADER"], True)], "barriers": [_buffer_barrier(["DRAW_INDIRECT"], [])]},
    ]}
    writers = writers_before_reads(plan)
    assert writers == [{}, {0: ("COMPUTE_SHADER",)}]
    (group,) = lower_barriers(plan["passes"][1]["barriers"], "barrier", TWO_FAMILIES, writers=writers[1])
    assert [(s.src_stages, s.src_access) for s in group] == [
        (("COMPUTE_SHADER", "DRAW_INDIRECT"), ("MEMORY_READ", "MEMORY_WRITE"))]


def test_barrier_after_reads_also_names_the_waits_made_on_its_queue():
    """H100 fuzz seed 231271/12: compute writes, graphics reads it (indirect), waits for compute
    twice more, then writes: the write-after-read barrier names the stages of every wait made
    so far on the graphics VkQueue (the layer's chain for the write is the last wait's)."""
    from rgraph.vk.lower.workarounds.after_reads import src_additions

    def wait(stages):
        return {"queue": "compute", "value": 1, "stages": stages}
    plan = {"passes": [
        {"queue": "compute", "waits": [], "accesses": [_buffer_access(["COMPUTE_SHADER"], True)], "barriers": []},
        {"queue": "graphics", "waits": [wait(["DRAW_INDIRECT"])], "accesses": [_buffer_access(["DRAW_INDIRECT"], False)],
         "barriers": [_buffer_barrier(["COMPUTE_SHADER"], ["SHADER_STORAGE_WRITE"], "compute")]},
        {"queue": "graphics", "waits": [wait(["COLOR_ATTACHMENT_OUTPUT"])], "accesses": [], "barriers": []},
        {"queue": "graphics", "waits": [], "accesses": [_buffer_access(["COMPUTE_SHADER"], True)],
         "barriers": [_buffer_barrier(["DRAW_INDIRECT"], [])]},
    ]}
    assert src_additions(plan, lambda queue: queue)[3] == {
        0: ("COLOR_ATTACHMENT_OUTPUT", "COMPUTE_SHADER", "DRAW_INDIRECT")}
    assert src_additions(plan, lambda queue: 0)[3] == {0: ("COMPUTE_SHADER",)}  # one VkQueue: no imports


def test_aliased_first_use_after_reads_names_the_waits_made_on_its_queue():
    """H100 fuzz seed 0/28 (aliased): a first use from UNDEFINED after the previous occupant's
    reads names the stages of the waits made on its VkQueue; its src access stays MEMORY_READ."""
    from rgraph.vk.lower.workarounds.after_reads import src_additions

    first_use = _barrier("b", ["COMPUTE_SHADER"], [], "UNDEFINED", "GENERAL")
    plan = {"passes": [
        {"queue": "graphics", "waits": [{"queue": "compute", "value": 1, "stages": ["VERTEX_SHADER"]}],
         "accesses": [], "barriers": []},
        {"queue": "graphics", "waits": [], "accesses": [_access("b", ["FRAGMENT_SHADER"], False)],
         "barriers": [first_use]},
    ]}
    extra = src_additions(plan, lambda queue: queue)[1]
    assert extra == {0: ("VERTEX_SHADER",)}
    (group,) = lower_barriers([first_use], "barrier", TWO_FAMILIES, writers=extra)
    assert [(s.src_stages, s.src_access) for s in group] == [(("COMPUTE_SHADER", "VERTEX_SHADER"), ("MEMORY_READ",))]


def test_aliased_first_use_after_a_write_and_reads_names_memory_read_too():
    """Random graph seed 0/32 (aliased, lavapipe and H100): the previous occupants ended with
    an attachment write and with storage reads; the transition keeps the write's access and
    adds MEMORY_READ."""
    first_use = _barrier("img1", ["COLOR_ATTACHMENT_OUTPUT", "FRAGMENT_SHADER"], ["COLOR_ATTACHMENT_WRITE"],
                         "UNDEFINED", "COLOR_ATTACHMENT_OPTIMAL")
    (group,) = lower_barriers([first_use], "barrier", TWO_FAMILIES)
    assert group[0].src_access == ("COLOR_ATTACHMENT_WRITE", "MEMORY_READ")


def _wait(stages):
    return {"queue": "compute", "value": 1, "stages": stages}


def test_aliased_buffer_first_use_after_reads_names_waits_and_the_write():
    """H100 fuzz 885/24 aliased: buf6 written (fragment), read as a uniform, graphics waits for
    compute, then buf1 (same memory) is first written by a dispatch. Its barrier (reads' stages,
    no access) names the wait's stages and buf6's write; an emptied post-write scope does not."""
    from rgraph.vk.lower.workarounds.after_reads import src_additions

    def buf(name, stages, write):
        return {"resource": name, "subresource": None, "stages": stages, "write": write}

    first_use = {**_buffer_barrier(["FRAGMENT_SHADER", "VERTEX_SHADER"], []), "resource": "buf1", "aliases": "buf6"}
    plan = {"passes": [
        {"queue": "graphics", "waits": [], "accesses": [buf("buf6", ["FRAGMENT_SHADER"], True)], "barriers": []},
        {"queue": "graphics", "waits": [], "accesses": [buf("buf6", ["VERTEX_SHADER"], False)], "barriers": []},
        {"queue": "graphics", "waits": [_wait(["COLOR_ATTACHMENT_OUTPUT"])], "accesses": [], "barriers": []},
        {"queue": "graphics", "waits": [], "accesses": [buf("buf1", ["COMPUTE_SHADER"], True)],
         "barriers": [first_use]},
    ]}
    assert src_additions(plan, lambda queue: queue)[3] == {0: ("COLOR_ATTACHMENT_OUTPUT", "FRAGMENT_SHADER")}
    (group,) = lower_barriers([first_use], "barrier", TWO_FAMILIES, writers={0: ("COLOR_ATTACHMENT_OUTPUT",)})
    assert group[0].src_access == ("MEMORY_READ", "MEMORY_WRITE")
    after_write = {**plan, "passes": [plan["passes"][0], plan["passes"][2], plan["passes"][3]]}
    assert src_additions(after_write, lambda queue: queue)[2] == {}  # latest access a write: not repaired


def test_layout_change_after_an_acquire_names_the_waits_of_its_queue():
    """H100 fuzz 422/25 and 156/32: a persistent image written on compute in one frame and
    acquired by graphics in the next, after graphics waited for compute elsewhere. The layout
    change recorded after the acquire names every wait stage of the graphics VkQueue."""
    from rgraph.vk.lower.workarounds.after_reads import src_additions

    acquire = _barrier("img", ["COMPUTE_SHADER"], ["SHADER_STORAGE_WRITE"], "GENERAL", "SHADER_READ_ONLY_OPTIMAL")
    acquire["src"]["queue"] = "compute"
    plan = {"passes": [
        {"queue": "graphics", "waits": [_wait(["COLOR_ATTACHMENT_OUTPUT"])], "accesses": [], "barriers": []},
        {"queue": "graphics", "waits": [], "accesses": [_access("img", ["FRAGMENT_SHADER"], False)],
         "barriers": [acquire]},
        {"queue": "compute", "waits": [], "accesses": [_access("img", ["COMPUTE_SHADER"], True)], "barriers": []},
        {"queue": "graphics", "waits": [_wait(["VERTEX_SHADER"])], "accesses": [], "barriers": []},
    ]}
    extra = src_additions(plan, lambda queue: queue)[1]
    assert extra == {0: ("COLOR_ATTACHMENT_OUTPUT", "VERTEX_SHADER")}  # frames repeat: the later wait too
    acquire_call, transition_call = lower_barriers([acquire], "barrier", TWO_FAMILIES, writers=extra)
    assert acquire_call[0].src_access == () and acquire_call[0].src_family == 1  # spec-mandated masks kept
    assert transition_call[0].src_stages == ("COLOR_ATTACHMENT_OUTPUT", "FRAGMENT_SHADER", "VERTEX_SHADER")
    assert transition_call[0].src_access == ("MEMORY_READ", "MEMORY_WRITE")


def test_partly_seen_handoff_gets_a_global_barrier_in_the_same_call():
    """H100 fuzz 1289/37 aliased: img16 (8x8 RGBA8, two mips: 2,048 bytes on NVIDIA, 320
    packed) takes over img6 (8x8 RGBA16F, two layers: 1,024 bytes, packed alike). The layer
    applies img16's hand-off to its 320 packed bytes only, so the hand-off also records a
    global memory barrier: the hand-off's src scope before ALL_COMMANDS."""
    from rgraph.vk.lower.workarounds.packed_ranges import packed_bytes, partial_handoffs

    img6 = {"name": "img6", "kind": "image", "format": "R16G16B16A16_SFLOAT", "extent": [8, 8, 1], "mips": 1,
            "layers": 2, "bytes": 1024, "heap": 1, "offset": 0}
    img16 = {**img6, "name": "img16", "format": "R8G8B8A8_UNORM", "mips": 2, "layers": 1, "bytes": 2048}
    assert (packed_bytes(img6), packed_bytes(img16)) == (1024, 320)
    assert packed_bytes({**img6, "format": "D24_UNORM_S8_UINT", "layers": 1}) == 8 * 8 * (4 + 1)
    handoff = _barrier("img16", ["COLOR_ATTACHMENT_OUTPUT"], ["COLOR_ATTACHMENT_WRITE"], "UNDEFINED", "GENERAL")
    handoff["aliases"] = "img6"
    plan = {"resources": [img6, img16], "passes": [{"barriers": [handoff]}]}
    assert partial_handoffs(plan) == [{0}]
    roomy = {**img16, "format": "R16G16B16A16_SFLOAT", "mips": 1, "layers": 2}  # packs over all of img6
    assert partial_handoffs({**plan, "resources": [img6, {**roomy, "name": "img16"}]}) == [set()]
    (group,) = lower_barriers([handoff], "barrier", TWO_FAMILIES, partial_handoffs={0})
    image, memory = group
    assert image.resource == "img16" and memory.resource is None
    assert (memory.src_stages, memory.src_access) == (image.src_stages, image.src_access)
    assert (memory.dst_stages, memory.dst_access) == (("ALL_COMMANDS",), ("MEMORY_READ", "MEMORY_WRITE"))
    assert lower_barriers([handoff], "barrier", TWO_FAMILIES) == [[image]]
