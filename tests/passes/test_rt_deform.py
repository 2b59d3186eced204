"""Deformable meshes in the ray tracing graphs (rgraph/vk/rt_deform.py) on lavapipe, scene
tests/data/rt/deform_tiny.yaml (a breathing, pressed neck beside a mirror and a glass sphere):

- the stand-alone image follows the deformation: two frames differ where the neck moves, each
  matches the NumPy float64 reference ray tracer fed the deformed geometry of its frame's scene
  time, and not the rest pose's;
- a per-frame (transient) accel is rebuilt from the same deformed geometry;
- the hybrids (compute visibility buffer, hardware raster) agree with the stand-alone at a
  deformed frame, and the visibility ids are the deformed triangles';
- the refit accel (with the GPU normals pass and its barriers, rgraph/vk/rt_normals.py) and the
  compute visibility buffer under validation + synchronization validation (zero messages) over
  51 frames, ids equal to the reference at the last frame;
- the GPU normals of each set (DeformedTables alone, under validation + synchronization
  validation) are the float64 reference's;
- a scene without deformable meshes keeps the static tables and inputs (its images are
  byte-identical to before: benchmarks/rt_image_hashes.py, docs/raytracing.md);
- the reference geometry (``Deformer.traced``) is the raster path's positions and the float64
  normal rule of the GPU's deform_normals pass.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rt_helpers import rt_validates

from rgraph.compiler.pipeline import compile_graph
from rgraph.resources import builtin_passes
from rgraph.scene.build import load_scene_data
from rgraph.vk.errors import VulkanUnavailable

builtin_passes()
from rgraph.passes.raytrace_hybrid import decode_visibility, prim_bits  # noqa: E402
from rgraph.passes.rt_model import build_tables, sky_cubemap  # noqa: E402
from rgraph.passes.rt_ref import render  # noqa: E402
from rgraph.passes.rt_vis_ref import edge_pixels, visibility_reference  # noqa: E402

SCENE = TESTS / "data" / "rt" / "deform_tiny.yaml"
BUILD_GRAPH = TESTS / "pass_graphs" / "rt_deform_build.yaml"
REBUILT_GRAPH = TESTS / "pass_graphs" / "rt_standalone_rebuilt.yaml"
SIZE = (48, 32)
SKY = 64  # rt.sky_size of the graphs
DEPTH = 4
LATE = 50  # content frame 50: 0.83 s, the press near its deepest, the breath near its widest
NECK = 1  # its instance (one per mesh, in scene order): the deformable one
SECONDARY = (2, 3)  # the mirror and the glass sphere


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(1.0 / mse)


def _run(graph, frame: int, extra=(), params=None, validate: bool | None = None, refit: bool = True) -> dict:
    """Outputs of content frame ``frame`` (the last of ``frame + 1`` frames); ``refit``: the
    plan's accel is persistent and refitted."""
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(str(graph), scene_path=SCENE, size=SIZE, extra_outputs=list(extra), params=params or {})
    assert any(r["kind"] == "accel" and r["accel"]["refit"] for r in plan["resources"]) == refit
    try:
        result = execute_plan(plan, validate=rt_validates() if validate is None else validate, frames=frame + 1,
                              read_outputs=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert [m.text for m in result.messages] == []
    return result.outputs


def _color(outputs: dict) -> np.ndarray:
    return outputs["color"][..., :3].astype(np.float64)


def _reference(seconds: float | None) -> np.ndarray:
    return render(build_tables(load_scene_data(SCENE, SIZE), seconds), sky_cubemap(SKY), SIZE, DEPTH)


def _seconds(frame: int) -> float:
    return load_scene_data(SCENE, SIZE).seconds(frame)


def _in_neck_shadow(data, x: int, y: int, frame: int) -> bool:
    """Whether pixel (x, y)'s first surface has a shadow ray blocked by the neck at ``frame``."""
    from rgraph.passes.rt_model import primary_dir
    from rgraph.passes.rt_ref import intersect, offset_ray

    t = build_tables(data, _seconds(frame))
    first = sum(m.data.triangle_count * len(m.positions) for m in data.meshes[:NECK])
    count = data.meshes[NECK].data.triangle_count
    d = primary_dir(t, x, y, *SIZE)
    hit = intersect(t, np.zeros(3), d)
    if hit is None:
        return False
    tri = t.triangles[hit[1]]
    n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    n = n / np.linalg.norm(n) * (-1.0 if n @ d > 0 else 1.0)
    p = offset_ray(hit[0] * d, n)
    for kind, vec, _radiance in t.lights:
        to_light = vec / np.linalg.norm(vec) if kind == 0 else (vec - p) / np.linalg.norm(vec - p)
        blocker = intersect(t, p, to_light)
        if blocker is not None and first <= blocker[1] < first + count:
            return True
    return False


@pytest.fixture(scope="module")
def standalone() -> dict[int, np.ndarray]:
    return {frame: _color(_run("rt_standalone", frame)) for frame in (0, LATE)}


@pytest.fixture(scope="module")
def references() -> dict[int, np.ndarray]:
    return {frame: _reference(_seconds(frame)) for frame in (0, LATE)}


@pytest.mark.vulkan
def test_standalone_follows_the_deformation_and_matches_the_reference(standalone, references):
    refs = references
    for frame, gpu in standalone.items():
        assert np.isfinite(gpu).all()
        assert np.abs(gpu - refs[frame]).max() < 0.01, frame  # float16 output
        assert psnr(gpu, refs[frame]) > 60, frame
    moved_gpu = np.abs(standalone[LATE] - standalone[0]).max(axis=-1) > 0.02
    change_ref = np.abs(refs[LATE] - refs[0]).max(axis=-1)
    assert not (moved_gpu & (change_ref < 0.005)).any() and not (~moved_gpu & (change_ref > 0.04)).any()
    # where the neck moves: on the neck (seen at either frame) and in the mirror / through the glass
    data = load_scene_data(SCENE, SIZE)
    bits = prim_bits(data)
    seen = [decode_visibility(visibility_reference(data, SIZE, bits, seconds=_seconds(f)), bits)[0] for f in (0, LATE)]
    neck = (seen[0] == NECK) | (seen[1] == NECK)
    traced = np.isin(seen[0], SECONDARY) & np.isin(seen[1], SECONDARY)
    assert moved_gpu[neck].sum() >= 10 and moved_gpu[traced].any()  # 38 and 1 pixel(s) at 48x32
    rest = np.argwhere(moved_gpu & ~neck & ~traced)  # elsewhere: only the neck's shadow
    assert all(any(_in_neck_shadow(data, x, y, f) for f in (0, LATE)) for y, x in rest), rest
    rest = _reference(None)  # before: the refit read the rest pose every frame
    assert psnr(standalone[LATE], rest) < 45


@pytest.mark.vulkan
def test_a_per_frame_accel_is_built_from_the_deformed_geometry(references):
    plan = compile_graph(str(REBUILT_GRAPH), scene_path=SCENE, size=SIZE)
    assert [(r["lifetime"], r["accel"]["refit"]) for r in plan["resources"] if r["kind"] == "accel"] == \
        [("transient", False)]
    gpu = _color(_run(REBUILT_GRAPH, LATE, refit=False))
    assert np.abs(gpu - references[LATE]).max() < 0.01 and psnr(gpu, references[LATE]) > 60


@pytest.mark.vulkan
@pytest.mark.parametrize("graph, params", [("rt_hybrid", {"rt.wavefront": "1"}), ("rt_hybrid", {"rt.wavefront": "0"}),
                                           ("rt_hybrid_raster", {})])
def test_hybrid_agrees_with_stand_alone_at_a_deformed_frame(standalone, references, graph, params):
    outputs = _run(graph, LATE, extra=("visibility",), params=params)
    hybrid = _color(outputs)
    assert np.isfinite(hybrid).all()
    assert psnr(standalone[LATE], hybrid) >= 45
    assert psnr(references[LATE], hybrid) > 60
    data = load_scene_data(SCENE, SIZE)
    ids = outputs["visibility"][..., 0]
    ref = visibility_reference(data, SIZE, prim_bits(data), seconds=_seconds(LATE))
    rest = visibility_reference(data, SIZE, prim_bits(data))
    assert (ref != rest).sum() > 0
    equal = ids == ref
    assert equal.mean() >= 0.99 and not (~equal & ~edge_pixels(ref)).any()


@pytest.mark.vulkan
@pytest.mark.parametrize("wide", ["1", "0"])
def test_refit_and_visibility_buffer_under_synchronization_validation(wide):
    frame = LATE
    outputs = _run(BUILD_GRAPH, frame, params={"rt.vis_atomic64": wide}, validate=True)
    data = load_scene_data(SCENE, SIZE)
    ids = outputs["visibility"][..., 0]
    ref = visibility_reference(data, SIZE, prim_bits(data), seconds=_seconds(frame))
    assert (ids != visibility_reference(data, SIZE, prim_bits(data))).sum() >= 10  # not the rest pose's
    equal = ids == ref
    assert equal.mean() >= 0.99 and not (~equal & ~edge_pixels(ref)).any()


def test_traced_geometry_is_the_raster_positions_and_the_reference_normals():
    from rgraph.scene.smoothing import normals_tangents

    data = load_scene_data(SCENE, SIZE)
    (neck,) = data.deformable
    seconds = _seconds(LATE)
    pos, nrm = neck.deformer.traced(seconds)
    written = np.empty_like(pos)
    neck.deformer.write_positions(seconds, written)
    assert pos.dtype == np.float32 and np.array_equal(pos, written)
    d = neck.deformer
    ref_normals, _tangents = normals_tangents(pos, d.rest.indices, d.topology, d.rest.normals, d.rest.uvs)
    assert np.array_equal(nrm, ref_normals)
    assert np.abs(pos - neck.data.positions).max() > 0.01  # it moved
    assert np.allclose(np.linalg.norm(nrm, axis=1), 1.0)


@pytest.mark.vulkan
def test_a_scene_without_deformable_meshes_keeps_the_static_tables(tmp_path):
    from rgraph.api import open_device

    static = tmp_path / "static.yaml"
    static.write_text(SCENE.read_text().replace("deformable: true", "deformable: false"))
    for scene, deformed in ((static, False), (SCENE, True)):
        plan = compile_graph("rt_standalone", scene_path=scene, size=SIZE)
        try:
            with open_device(validate=rt_validates(), verbose=False, ray_tracing=True) as gpu:
                accels = gpu.load(plan).executor.accels
                assert (accels.deformed is not None) == deformed
                assert accels.deforming == ({"scene_as"} if deformed else set())
        except VulkanUnavailable as exc:  # pragma: no cover
            pytest.skip(str(exc))


@pytest.mark.vulkan
def test_gpu_normals_match_the_float64_reference():
    """DeformedTables alone under validation + synchronization validation: each set's GPU
    normals (rgraph/vk/rt_normals.py) from its host-written positions, against the reference."""
    from types import SimpleNamespace

    import rgraph
    from rgraph.vk.device_local import DeviceLocal, one_time_submitter
    from rgraph.vk.loader import vk
    from rgraph.vk.rt_deform import DeformedTables

    v = vk()
    data = load_scene_data(SCENE, SIZE)
    first = np.concatenate([[0], np.cumsum([m.data.vertex_count for m in data.meshes])])
    rest = np.concatenate([m.data.normals for m in data.meshes]).astype(np.float32)
    plan = {"scene_source": str(SCENE), "size": list(SIZE), "camera": 0}
    got = {}
    try:
        with rgraph.open_device(validate=True, verbose=False, ray_tracing=True) as gpu:
            tables = DeformedTables(gpu.device, plan, 2)
            local = DeviceLocal(gpu.device)
            try:
                with one_time_submitter(gpu.device) as submit:
                    for s, frame in ((0, LATE), (1, 7), (0, 3)):
                        tables.update(frame, s)
                        submit("graphics", lambda cb, s=s: tables.record_normals(cb, s))
                        handle, size = tables.normal_buffers()[s]
                        raw = local.read(submit, SimpleNamespace(handle=handle, size=size),
                                         v.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, v.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT)
                        got[frame] = np.frombuffer(raw, dtype=np.float32)[:rest.size].reshape(-1, 3).copy()
            finally:
                local.destroy()
                tables.destroy()
            messages = [str(m) for m in gpu.close()]
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert messages == []
    lo, hi = int(first[NECK]), int(first[NECK + 1])
    for frame, normals in got.items():
        _pos, ref = data.meshes[NECK].deformer.traced(_seconds(frame))
        np.testing.assert_allclose(normals[lo:hi], ref, rtol=0, atol=2e-6)  # the raster pass's tolerance
        assert np.array_equal(np.delete(normals, np.s_[lo:hi], axis=0), np.delete(rest, np.s_[lo:hi], axis=0))
    assert np.abs(got[LATE][lo:hi] - rest[lo:hi]).max() > 0.05  # they moved
