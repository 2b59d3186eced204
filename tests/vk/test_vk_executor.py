"""The runtime on lavapipe with validation + synchronization validation: every hand-built plan
runs clean with exact data, and a planted missing barrier is caught (by syncval and/or data)."""

from __future__ import annotations

import pytest
from vkplans import PlanBuilder, drop_barrier

from rgraph.vk.errors import VulkanUnavailable

pytestmark = pytest.mark.vulkan


def _execute(plan, frames=1, **kw):
    from rgraph.vk.executor import execute_plan

    try:
        return execute_plan(plan, validate=True, frames=frames, **kw)
    except VulkanUnavailable as exc:  # pragma: no cover - environment without Vulkan
        pytest.skip(str(exc))


def raster_color_depth():
    b = PlanBuilder((64, 64))
    b.image("albedo", "R8G8B8A8_UNORM").image("depth", "D32_SFLOAT").image("out", "R8G8B8A8_UNORM", lifetime="output")
    b.add_pass("gbuffer", "raster", [("albedo", "color_attachment"), ("depth", "depth_attachment")])
    b.add_pass("lighting", "raster", [("depth", "depth_read"), ("depth", "sampled"), ("albedo", "sampled"),
                                      ("out", "color_attachment")])
    return b.build(), ("lighting", "albedo")


def compute_storage():
    b = PlanBuilder((64, 64))
    b.image("field", "R32_UINT").buffer("counts", 1024).image("out", "R16G16B16A16_SFLOAT", lifetime="output")
    b.buffer("sum", 512, lifetime="output")
    b.add_pass("produce", "compute", [("field", "storage_write"), ("counts", "storage_write")])
    b.add_pass("consume", "compute", [("field", "storage_read"), ("counts", "storage_read"),
                                      ("out", "storage_write"), ("sum", "storage_write")])
    return b.build(), ("consume", "field")


def transfer_copy():
    b = PlanBuilder((32, 32))
    b.image("src", "R8G8B8A8_UNORM").buffer("sbuf", 256)
    b.image("dst", "R8G8B8A8_UNORM", lifetime="output").buffer("dbuf", 256, lifetime="output")
    b.image("filled", "R16_SFLOAT", lifetime="output")
    b.add_pass("produce", "compute", [("src", "storage_write"), ("sbuf", "storage_write")])
    b.add_pass("copy", "transfer", [("src", "transfer_src"), ("sbuf", "transfer_src"), ("dst", "transfer_dst"),
                                    ("dbuf", "transfer_dst"), ("filled", "transfer_dst")])
    return b.build(), ("copy", "src")


def array_layers():
    b = PlanBuilder((32, 32))
    b.image("layers", "R8G8B8A8_UNORM", layers=2).image("out", "R32_UINT", lifetime="output")
    b.add_pass("layer0", "raster", [("layers", "color_attachment", {"layers": [0, 1]})])
    b.add_pass("layer1", "compute", [("layers", "storage_write", {"layers": [1, 2]})])
    b.add_pass("gather", "compute", [("layers", "sampled", {"layers": [0, 2]}), ("out", "storage_write")])
    return b.build(), ("gather", "layers")


def cross_queue():
    b = PlanBuilder((32, 32))
    b.buffer("params", 256).image("out", "R8G8B8A8_UNORM", lifetime="output")
    b.add_pass("simulate", "compute", [("params", "storage_write")], queue="compute")
    b.add_pass("draw", "raster", [("params", "uniform"), ("out", "color_attachment")])
    return b.build(), ("draw", "params")


def aliasing():
    b = PlanBuilder((32, 32))
    b.image("first", "R8G8B8A8_UNORM").image("second", "R8G8B8A8_UNORM")
    b.buffer("a_out", 128, lifetime="output").buffer("b_out", 128, lifetime="output")
    b.add_pass("write_first", "compute", [("first", "storage_write")])
    b.add_pass("read_first", "compute", [("first", "sampled"), ("a_out", "storage_write")])
    b.add_pass("write_second", "compute", [("second", "storage_write")])
    b.add_pass("read_second", "compute", [("second", "sampled"), ("b_out", "storage_write")])
    return b.build(alias_groups=[("first", "second")]), ("write_second", "second")


def persistent_history():
    b = PlanBuilder((32, 32))
    b.image("history", "R32_UINT", lifetime="persistent").image("out", "R32_UINT", lifetime="output")
    b.add_pass("accumulate", "compute", [("history", "storage_rw")])
    b.add_pass("present", "compute", [("history", "storage_read"), ("out", "storage_write")])
    return b.build(), ("accumulate", "history")


def geometry_inputs(indirect: bool = False):
    """Vertex and index buffers a compute pass wrote, drawn directly (``indirect``: through
    arguments it wrote too)."""
    b = PlanBuilder((32, 32))
    b.buffer("verts", 256).buffer("indices", 256).image("out", "R8G8B8A8_UNORM", lifetime="output")
    args = [("args", "storage_write")] if indirect else []
    if indirect:
        b.buffer("args", 256)
    b.add_pass("build", "compute", [("verts", "storage_write"), ("indices", "storage_write"), *args])
    b.add_pass("draw", "raster", [("verts", "vertex"), ("indices", "index"),
                                  *[(name, "indirect") for name, _ in args], ("out", "color_attachment")])
    return b.build(), ("draw", "verts")


def indirect_arguments():
    plan, _ = geometry_inputs(indirect=True)
    return plan, ("draw", "args")


SCENARIOS = {f.__name__: f for f in (raster_color_depth, compute_storage, transfer_copy, array_layers,
                                     cross_queue, aliasing, persistent_history, geometry_inputs,
                                     indirect_arguments)}
FRAMES = {"persistent_history": 3}


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_plan_runs_clean_with_exact_data(name):
    plan, _ = SCENARIOS[name]()
    result = _execute(plan, frames=FRAMES.get(name, 2))
    assert [str(m) for m in result.messages] == []
    assert result.data_ok is True, [str(m) for m in result.mismatches]
    assert not result.unchecked
    assert set(result.timings["passes"]) == {p["name"] for p in plan["passes"]}


# Which oracle catches each planted drop on lavapipe. Lavapipe runs each queue serially, so
# the data check never sees a dropped barrier here (it guards the runtime and matters on GPUs);
# layout-changing drops are also caught by core validation's layout tracking.
CAUGHT_BY = {
    "raster_color_depth": {"syncval", "validation"},
    "compute_storage": {"syncval"},  # GENERAL -> GENERAL: a pure memory dependency
    "transfer_copy": {"syncval", "validation"},
    "array_layers": {"syncval", "validation"},
    # The acquire barrier of the ownership pair: both plan queues share lavapipe's one VkQueue, where
    # the runtime records no semaphore wait between them (submission order and the plan's barriers
    # order them), so syncval sees the missing barrier (on a multi-family GPU it is a missing acquire).
    "cross_queue": {"syncval"},
    # Layers since 1.3.2xx track each resource in an address range of its own: a hand-off between
    # aliases is seen by core validation's layout tracking only (1.3.239's syncval saw it too).
    "aliasing": {"validation"},
    "persistent_history": {"syncval"},  # frame N+1 vs frame N, caught at submit time
    "geometry_inputs": {"syncval"},
    "indirect_arguments": {"syncval"},
}
#: what Debian 12's layer caught where it differs (when --validate falls back to it)
CAUGHT_BY_1_3_239 = {"aliasing": {"syncval", "validation"}}


def _caught_by(name: str) -> set[str]:
    from rgraph.vk.instance import validation_layer_version

    old = validation_layer_version() is not None and validation_layer_version() <= (1, 3, 239)
    return CAUGHT_BY_1_3_239.get(name, CAUGHT_BY[name]) if old else CAUGHT_BY[name]


def _caught(result):
    caught = set()
    if any(m.id_name.startswith("SYNC-") for m in result.messages):
        caught.add("syncval")
    if any(not m.id_name.startswith("SYNC-") for m in result.messages):
        caught.add("validation")
    if result.data_ok is False:
        caught.add("data")
    return caught


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_dropped_barrier_is_caught(name):
    plan, (pass_name, resource) = SCENARIOS[name]()
    result = _execute(drop_barrier(plan, pass_name, resource), frames=FRAMES.get(name, 2))
    assert _caught(result) == _caught_by(name), [str(m) for m in result.messages][:3]
    if result.messages:
        assert any(m.pass_name == pass_name for m in result.messages), [m.pass_name for m in result.messages]


def test_dropped_semaphore_and_acquire_is_caught():
    plan, (pass_name, resource) = cross_queue()
    broken = drop_barrier(plan, pass_name, resource)
    for p in broken["passes"]:
        p["waits"], p["signals"], p["releases"] = [], [], []
    assert _caught(_execute(broken)) == {"syncval"}


def test_a_buffer_drop_beside_an_image_barrier_is_caught():
    """With an image barrier of the same scopes kept in the same vkCmdPipelineBarrier2, a
    dropped buffer barrier is reported (the 1.3.239 layer did not: a blind spot until session 21;
    alone, it reported the same drop)."""
    from rgraph.vk.instance import validation_layer_version

    plan, _ = compute_storage()
    alone = PlanBuilder((64, 64))
    alone.buffer("counts", 1024).buffer("sum", 512, lifetime="output")
    alone.add_pass("produce", "compute", [("counts", "storage_write")])
    alone.add_pass("consume", "compute", [("counts", "storage_read"), ("sum", "storage_write")])
    assert _caught(_execute(drop_barrier(alone.build(), "consume", "counts"))) == {"syncval"}
    old = validation_layer_version() <= (1, 3, 239)
    assert _caught(_execute(drop_barrier(plan, "consume", "counts"))) == (set() if old else {"syncval"})


def test_syncval_misses_vertex_reads_of_an_indirect_draw():
    """Blind spot of the 1.4 layer: the vertex and index buffers of an indirect draw are not
    tracked (their ranges are known only on the device), so a dropped barrier in front of them
    goes unreported; drawn directly, the same drop is (test_dropped_barrier_is_caught). If this
    starts failing, the layer got better."""
    from rgraph.vk.instance import validation_layer_version

    if validation_layer_version() <= (1, 3, 239):
        pytest.skip("Debian 12's layer reports it")
    plan, _ = geometry_inputs(indirect=True)
    for resource in ("verts", "indices"):
        assert _caught(_execute(drop_barrier(plan, "draw", resource))) == set(), resource


@pytest.mark.parametrize("cuts", ["queue", "plan"])
def test_unvalidated_frames_group_submits_and_keep_data_exact(cuts, monkeypatch):
    """Without validation, consecutive batches on one VkQueue go in one vkQueueSubmit2 (an
    array of submit infos, semaphores between them): data stays exact, timestamps are read.
    On one VkQueue (lavapipe) the plan's cross-queue waits need no semaphore: the default
    cuts (``queue``) give the frame one batch, one command buffer; ``RGRAPH_BATCH_CUTS=plan``
    (the cuts before session 11) cuts at every plan wait and signal."""
    from rgraph.vk.executor import Executor, marks_per_frame
    from rgraph.vk.loader import vk

    monkeypatch.setenv("RGRAPH_BATCH_CUTS", cuts)
    plan, _ = cross_queue()
    result = _execute_unvalidated(plan, frames=4)
    assert result.data_ok is True, [str(m) for m in result.mismatches]
    assert all(ms is not None and ms >= 0 for ms in result.timings["passes"].values())
    try:
        executor = Executor(plan, validate=False, device_index=None, verbose=False)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    try:
        calls = executor.submit_calls[0]
        ffi = vk().ffi
        one_queue = len({int(ffi.cast("uintptr_t", c.queue)) for c in calls}) == 1
        assert sum(c.count for c in calls) == len(executor.batches) >= (1 if one_queue and cuts == "queue" else 2)
        if one_queue:
            assert len(calls) == 1  # one VkQueue (lavapipe): one call per frame
            assert not executor.semaphores  # one VkQueue: no semaphore
            if cuts == "queue":
                assert len(executor.batches) == 1
        marks: list[float] = []
        timings = executor.run_frames(5, marks=marks)
        assert len(marks) == 5 * marks_per_frame(len(calls)) and marks == sorted(marks)
        assert timings["frames"] == 5 and timings["total_ms"] is not None
    finally:
        executor.close()


def test_polled_fence_wait_keeps_data_exact(monkeypatch):
    """``RGRAPH_FENCE_WAIT=poll`` (a diagnostic: the frame loop polls its fences instead of
    sleeping in vkWaitForFences) runs the same frames; an unknown way is refused."""
    from rgraph.vk.errors import ExecutionError

    plan, _ = cross_queue()
    monkeypatch.setenv("RGRAPH_FENCE_WAIT", "poll")
    result = _execute_unvalidated(plan, frames=4)
    assert result.data_ok is True, [str(m) for m in result.mismatches]
    monkeypatch.setenv("RGRAPH_FENCE_WAIT", "spin")
    with pytest.raises(ExecutionError, match="RGRAPH_FENCE_WAIT must be block or poll"):
        _execute_unvalidated(plan, frames=1)


def _execute_unvalidated(plan, frames):
    from rgraph.vk.executor import execute_plan

    try:
        return execute_plan(plan, validate=False, frames=frames, check_data=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))


EMPTY_GRAPH = """rgraph: 1
name: all_culled
resources:
  img: {kind: image, format: r8g8b8a8_unorm, size: [16, 16]}
passes:
  p: {kind: compute, writes: {img: storage_write}}
outputs: []
"""


def test_plan_with_every_pass_culled_runs_clean(tmp_path):
    """Zero passes: no submits, no fences to wait for (a fence wait of count 0 is invalid)."""
    from rgraph.compiler.pipeline import compile_graph

    path = tmp_path / "g.yaml"
    path.write_text(EMPTY_GRAPH)
    plan = compile_graph(path, size=(16, 16))
    assert plan["passes"] == [] and [c["pass"] for c in plan["culled"]] == ["p"]
    result = _execute(plan, frames=3)
    assert [str(m) for m in result.messages] == []
    assert result.timings["passes"] == {} and result.timings["total_ms"] is None


def test_run_command_reports_what_was_culled(tmp_path, capsys):
    from rgraph.cli import main

    path = tmp_path / "g.yaml"
    path.write_text(EMPTY_GRAPH)
    try:
        status = main(["run", str(path), "--size", "16x16", "--validate", "--frames", "2"])
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    err = capsys.readouterr().err
    if "no Vulkan device" in err:  # pragma: no cover
        pytest.skip(err)
    assert status == 0, err
    assert "every pass was culled" in err and "culled p: reaches no output" in err
    assert "0 validation message(s)" in err
