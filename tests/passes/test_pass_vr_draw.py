"""GPU-driven drawing and stereo (issue 18) on lavapipe under validation + synchronization validation.

- draw_cull's indirect commands and count (graphs/clustered.yaml, draw.mode=gpu) against the
  float64 NumPy frustum test (rgraph.scene.instances.visible): every instance whose sphere,
  shrunk by a hair, meets the frustum is drawn, none whose grown sphere misses it; each command
  is its mesh's (index count, first index, vertex offset) with instanceCount 1 and the
  instance id as firstInstance; stereo culls against the union of both eyes;
- the image of draw.mode=gpu (float64 and float32 hi/lo translations) and of naive (per-object
  CPU culling, one draw per object) equals draw.mode=cpu within one 8-bit code;
- views=2: layer 0 equals the mono image rendered from the left eye's camera, layer 1 the right
  eye's, each within one code, and the two layers differ;
- draw.order=front_to_back: the same commands, in non-decreasing distance bucket
  (rgraph.scene.instances.draw_buckets, within one bucket of float32 rounding), and the same image;
- instances moved after loading (SceneGPU.refresh_instances: one upload, not per frame) are
  drawn where they are.
"""

from __future__ import annotations

import numpy as np
import pytest
from clustered_helpers import graph_with_outputs, render, scene_file, srgb_codes

from rgraph.scene.build import load_scene_data
from rgraph.scene.instances import draw_buckets, eye_offsets, eye_view_projs, visible

SIZE = (64, 48)
LIGHTS = """  - {type: directional, direction: [-0.3, -1, -0.2], intensity: 1.5}
  - {generate: point, count: 12, seed: 2, bounds: [[-8, 0.2, -8], [8, 3, 8]], radius: [2, 5], intensity: [5, 20]}
"""
# instances all around the camera (many behind it or beside the frustum), unique boxes, a floor
MESHES = """materials:
  box:   {base_color: [0.7, 0.7, 0.72], roughness: 0.4, metallic: 0}
  floor: {base_color: [0.5, 0.5, 0.5], roughness: 0.7, metallic: 0}
meshes:
  - {shape: plane, params: {size: [60, 60], subdivisions: 1}, material: floor}
  - {shape: box, params: {size: [0.6, 0.6, 0.6]}, material: box, rotation: [10, 30, 0],
     instances: {count: 400, seed: 7, bounds: [[-12, 0.3, -12], [12, 3, 12]]}}
  - {shape: box, params: {size: [0.5, 0.8, 0.5]}, material: box, unique: true, seed: 3,
     instances: {count: 60, seed: 8, bounds: [[-10, 0.4, -10], [10, 0.4, 10]]}}
  - {shape: sphere, params: {radius: 0.7}, material: box, position: [0, 0.7, 0], instances: {grid: [3, 1, 3], spacing: 4}}
"""
CAMERA = "camera: {position: [0, 2, 3], look_at: [1, 0.5, -4], fov_y: 50, near: 0.1}\n"
HAIR = 1e-4


def _commands(outputs: dict, draws: int) -> tuple[int, np.ndarray]:
    raw = np.frombuffer(bytes(outputs["draw_args"]), dtype=np.uint32)
    return int(raw[0]), raw[4:4 + 5 * draws].reshape(-1, 5)


def _expected(scene, projs) -> tuple[np.ndarray, np.ndarray]:
    """(must draw, may draw) masks from the float64 test with radii shrunk / grown."""
    cam = scene.camera(0).position

    def mask(scale: float) -> np.ndarray:
        from rgraph.scene import instances as inst

        t, c, r = inst.instance_arrays(scene)
        saved = r.copy()
        r *= scale
        r += (scale - 1.0) * 1e-3
        try:
            return visible(scene, cam, projs)
        finally:
            r[:] = saved

    return mask(1 - HAIR), mask(1 + HAIR)


@pytest.mark.vulkan
@pytest.mark.parametrize("views,order", [(1, "none"), (2, "none"), (1, "front_to_back"), (2, "front_to_back")])
def test_gpu_culling_matches_the_numpy_frustum_test(tmp_path, views, order):
    scene_path = scene_file(tmp_path, LIGHTS, camera=CAMERA, meshes=MESHES)
    graph = graph_with_outputs(tmp_path, ("draw_args",))
    params = {"views": str(views), "views.ipd": "2.0", "draw.order": order}  # wide eyes: the union differs
    _plan, out = render(scene_path, size=SIZE, graph=graph, params=params)
    scene = load_scene_data(scene_path, SIZE)
    count, cmds = _commands(out, scene.draw_count)
    drawn = cmds[:count]
    ids = drawn[:, 4]
    assert len(np.unique(ids)) == count, "an instance was drawn twice"
    projs = eye_view_projs(scene, 0, views, 2.0) if views > 1 else [scene.camera(0).view_proj]
    must, may = _expected(scene, projs)
    got = np.zeros(scene.draw_count, dtype=bool)
    got[ids] = True
    assert np.all(got[must]), f"visible instances not drawn: {np.nonzero(must & ~got)[0][:10]}"
    assert not np.any(got & ~may), f"culled instances drawn: {np.nonzero(got & ~may)[0][:10]}"
    assert 0 < count < scene.draw_count  # the test has teeth: some culled, some kept
    # each command is its instance's mesh
    mesh_of = np.concatenate([np.full(m.instances, k) for k, m in enumerate(scene.meshes)])
    offsets = {}
    first_index = 0
    for k, m in enumerate(scene.meshes):
        offsets[k] = (m.data.triangle_count * 3, first_index)
        first_index += m.data.triangle_count * 3
    for row in drawn:
        index_count, first = offsets[int(mesh_of[row[4]])]
        assert (row[0], row[1], row[2]) == (index_count, 1, first)
    if order == "front_to_back":
        buckets = draw_buckets(scene)[ids]
        assert np.all(np.diff(buckets) >= -1), "commands not near to far"
        assert len(np.unique(buckets)) > 10  # the test has teeth: many buckets ...
        assert np.any(np.diff(ids.astype(np.int64)) < 0)  # ... and an order other than the instances'
    if views > 1:  # the union of both eyes is more than either eye alone
        left = visible(scene, scene.camera(0).position, projs[:1])
        right = visible(scene, scene.camera(0).position, projs[1:])
        assert np.any(got & ~left) and np.any(got & ~right)


@pytest.mark.vulkan
def test_draw_modes_render_the_same_image(tmp_path):
    scene_path = scene_file(tmp_path, LIGHTS, camera=CAMERA, meshes=MESHES)
    images = {}
    for label, params in (("cpu", {"draw.mode": "cpu"}), ("gpu", {}), ("gpu32", {"draw.float64": "false"}),
                          ("sorted", {"draw.order": "front_to_back"}), ("naive", {"draw.mode": "naive"})):
        _plan, out = render(scene_path, size=SIZE, params=params)
        images[label] = srgb_codes(out)
    assert images["cpu"].std() > 5  # a real picture
    for label in ("gpu", "gpu32", "sorted", "naive"):
        diff = np.abs(images[label] - images["cpu"])
        assert diff.max() <= 1, f"{label}: max diff {diff.max()} codes"


def _moved_camera(offset: np.ndarray) -> str:
    pos = np.array([0.0, 2.0, 3.0]) + offset
    at = np.array([1.0, 0.5, -4.0]) + offset
    f = ", ".join(repr(float(x)) for x in pos)
    g = ", ".join(repr(float(x)) for x in at)
    return f"camera: {{position: [{f}], look_at: [{g}], fov_y: 50, near: 0.1}}\n"


@pytest.mark.vulkan
def test_stereo_layers_equal_mono_images_from_each_eye(tmp_path):
    ipd = 0.4
    scene_path = scene_file(tmp_path, LIGHTS, camera=CAMERA, meshes=MESHES)
    _plan, out = render(scene_path, size=SIZE, params={"views": "2", "views.ipd": str(ipd)})
    stereo = srgb_codes(out)
    assert stereo.shape[0] == 2
    assert np.abs(stereo[0] - stereo[1]).max() > 20  # the eyes see different pictures
    scene = load_scene_data(scene_path, SIZE)
    for eye, offset in enumerate(eye_offsets(scene, 0, 2, ipd)):
        mono_path = scene_file(tmp_path, LIGHTS, camera=_moved_camera(offset), meshes=MESHES, name=f"eye{eye}")
        _plan, mono = render(mono_path, size=SIZE)
        diff = np.abs(stereo[eye] - srgb_codes(mono))
        assert diff.max() <= 1, f"eye {eye}: max diff {diff.max()} codes at {np.argwhere(diff > 1)[:5].tolist()}"


@pytest.mark.vulkan
@pytest.mark.slow
def test_vr_benchmark_smoke(capsys):
    """benchmarks/vr_tests.py end to end at a tiny size: a row per view count and mode, figures > 0."""
    from benchmarks.vr_tests import main

    assert main(["--size", "32x18", "--frames", "2", "--warmup", "0.3", "--tests", "lighting", "--views", "1,2"]) == 0
    out = capsys.readouterr().out
    for line in ("lighting views=1 gpu", "lighting views=1 naive", "lighting views=2 gpu", "lighting views=2 naive"):
        assert line in out
    assert "| lighting | 2 | 969 |" in out


def test_vr_benchmark_reports_the_logic_thread_and_the_skinning_worker():
    from benchmarks.vr_tests import logic_summary

    assert logic_summary(None) == ""
    base = {"hz": 60.0, "measured_hz": 59.9, "late_ticks": 0, "tick_us": 612.0}
    line = logic_summary({**base, "skin": {"worker": "process", "threads": 2, "tick_us": 9000.0,
                                           "tick_cpu_us": 17000.0, "wait_us": 40.0}})
    assert line == ("; logic 59.9 Hz of 60, 0 late, tick 612 us on the logic thread (skinning in a worker "
                    "process, 2 thread(s): 9000 us per state, 17000 us CPU, logic thread waits 40 us)")
    assert logic_summary({**base, "skin": {"worker": "thread", "threads": 1}}).endswith(
        "(skinning on the logic thread, 1 thread(s))")
    kept = {**base, "ticks_per_running_second": 55.2, "runs": 8, "behind_at_stop": 0, "tick_delay_us": 61.0}
    assert logic_summary(kept) == ("; logic 59.9 Hz of 60 (55.2 ticks per running second over 8 runs, 0 behind at "
                                   "stop, ticks 61 us past due), 0 late, tick 612 us on the logic thread")


@pytest.mark.vulkan
def test_vr_benchmark_failed_row_costs_that_row_only(capsys):
    """Each row runs in its own process: a row whose process fails (an unknown draw mode here,
    a lost device on a GPU) is reported as failed and the other rows still measure."""
    from benchmarks.vr_tests import main

    assert main(["--size", "32x18", "--frames", "2", "--warmup", "0.3", "--tests", "lighting", "--views", "1",
                 "--modes", "bogus,gpu"]) == 0
    out = capsys.readouterr().out
    assert "lighting views=1 bogus: FAILED: exit 2:" in out or "lighting views=1 bogus: FAILED: exit 1:" in out
    assert "lighting views=1 gpu: " in out and "vkQueueSubmit2 per frame" in out
    row = next(line for line in out.splitlines() if line.startswith("| lighting | 1 |"))
    assert float(row.split("|")[4]) > 0  # the gpu row after the failed one was measured


@pytest.mark.vulkan
@pytest.mark.parametrize("mode", ["gpu", "cpu"])
def test_moved_instances_are_uploaded_once_and_drawn_where_they_are(tmp_path, mode):
    """SceneGPU.refresh_instances after moving a mesh's instances: the next frame equals a fresh
    run of the scene with the mesh authored at the new place."""
    from clustered_helpers import GRAPH
    from rgraph.passes.tonemap_ref import srgb_codes as codes

    import rgraph
    from rgraph.compiler.pipeline import compile_graph

    def plan_of(path):
        return compile_graph(GRAPH, scene_path=path, size=SIZE, params={"draw.mode": mode})

    scene_path = scene_file(tmp_path, LIGHTS, camera=CAMERA, meshes=MESHES)
    moved_path = scene_file(tmp_path, LIGHTS, camera=CAMERA, meshes=MESHES.replace(
        "position: [0, 0.7, 0], instances: {grid", "position: [0.5, 0.7, -1], instances: {grid"), name="moved")
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        with gpu.load(plan_of(scene_path)) as exe:
            exe.run(2)
            scene = exe.executor.scene_gpu
            spheres = scene.data.meshes[-1]
            spheres.positions = spheres.positions + np.array([0.5, 0.0, -1.0])
            scene.refresh_instances()
            exe.run(2)
            got = codes(exe.read_outputs()["color"][..., :3])
        with gpu.load(plan_of(moved_path)) as exe:
            exe.run(1)
            want = codes(exe.read_outputs()["color"][..., :3])
        with gpu.load(plan_of(scene_path)) as exe:
            exe.run(1)
            before = codes(exe.read_outputs()["color"][..., :3])
        messages = gpu.close()
    assert [m.text for m in messages] == []
    assert np.abs(before - want).max() > 20  # the move shows
    assert np.abs(got - want).max() <= 1
