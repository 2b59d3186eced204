"""Stereo (issue 18) of forward_pbr, decals, sss_blur and composite on lavapipe, under validation
+ synchronization validation (zero messages).

tests/pass_graphs/stereo_forward_post.yaml runs depth_prepass -> forward_pbr -> decals ->
sss_blur h, v -> composite (with light_setup, a shadow-casting sun and IBL) at 48 x 32 on a small
scene of our own: a skin sphere (SSS) carrying a blood decal, a steel box, a drape behind, a
sun and two point lights. ``ao`` is imported with a different pattern per layer (a gradient
along x for the left eye, along y for the right; ``forward.ao_combine`` 2 multiplies it in), so
an eye reading the other eye's layer shows. Every test runs on that graph and on
stereo_forward_post_clustered.yaml (forward_pbr over the froxel lights lists of cluster_build and
light_assign, as graphs/surgery_clustered.yaml wires it).

The oracle (as tests/passes/test_pass_vr_draw.py::test_stereo_layers_equal_mono_images_from_each_eye):
with ``views=2`` layer k of every per-eye output (hdr, diffuse, specular, normal_sss, sss_tmp,
depth) equals the ``views=1`` run of the same graph on the scene with the camera moved to eye k
(``rgraph.scene.instances.eye_offsets``: same rotation and projection) and ao = layer k.

Tolerance: the two runs compute the same things from different float32 data (the eye's
view-projection is the centre's times a translation, computed in float64 and rounded, where the
mono run rounds the moved camera's; lights, decal boxes and shadow matrices are relative to the
centre camera instead of the eye), so results may differ by float32 rounding: depth within
1e-5 relative, the fp16 colour outputs within 2e-3 relative + 2e-3 absolute (about two fp16 ulps
at 1.0), normal_sss within one 8-bit code. On lavapipe they agree exactly today (depth within
1e-8); a pass that ignores the eye (the centre camera's view vector or position, or layer 0 of
an input for both eyes) misses by far more (see the report of the change).
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS

GRAPHS = {"uniform": TESTS / "pass_graphs" / "stereo_forward_post.yaml",
          "clustered": TESTS / "pass_graphs" / "stereo_forward_post_clustered.yaml"}
SIZE = (48, 32)
IPD = 0.064
CAMERA = (np.array([0.0, 0.05, 0.3]), np.array([0.0, 0.0, 0.0]))  # position, look_at
SCENE = """scene: 1
name: {name}
camera: {{position: [{position}], look_at: [{look_at}], fov_y: 40, near: 0.01}}
lights:
  - {{type: directional, direction: [-0.35, -1.0, -0.45], color: [1.0, 0.96, 0.9], intensity: 3.0, shadows: true}}
  - {{type: point, position: [0.07, 0.12, 0.16], color: [1.0, 0.97, 0.92], intensity: 0.6, radius: 0.5}}
  - {{type: point, position: [-0.09, 0.02, 0.14], color: [1.0, 0.85, 0.75], intensity: 0.25, radius: 0.4}}
materials:
  skin:  {{base_color: [0.82, 0.58, 0.50], roughness: 0.48, metallic: 0, sss: 0.8}}
  steel: {{base_color: [0.62, 0.63, 0.66], roughness: 0.18, metallic: 1}}
  drape: {{base_color: [0.16, 0.42, 0.45], roughness: 0.9, metallic: 0}}
meshes:
  - {{shape: sphere, params: {{radius: 0.05}}, material: skin}}
  - {{shape: box, params: {{size: [0.03, 0.06, 0.02]}}, material: steel, position: [0.06, 0.01, 0.03], rotation: [20, 30, 0]}}
  - {{shape: plane, params: {{size: [0.7, 0.7], subdivisions: 2}}, material: drape, position: [0.0, 0.0, -0.075],
     rotation: [90, 0, 0]}}
decals:
  - {{material: blood, position: [-0.01, 0.005, 0.05], size: [0.03, 0.015, 0.03]}}
"""
PER_EYE = ("hdr", "diffuse", "specular", "normal_sss", "sss_tmp", "depth")
TOLERANCE = {"depth": (1e-5, 0.0), "normal_sss": (0.0, 1.0 / 255 + 1e-6)}  # (rtol, atol)
DEFAULT_TOLERANCE = (2e-3, 2e-3)


def _scene(tmp_path, name: str, offset=(0.0, 0.0, 0.0)):
    def text(v):
        return ", ".join(repr(float(x)) for x in v)

    p = tmp_path / f"{name}.yaml"
    p.write_text(SCENE.format(name=name, position=text(CAMERA[0] + np.asarray(offset)), look_at=text(CAMERA[1] + np.asarray(offset))))
    return p


def _ao() -> np.ndarray:
    """(2, h, w, 1): a gradient along x for the left eye, along y for the right one."""
    w, h = SIZE
    ys, xs = np.mgrid[0:h, 0:w]
    return np.stack([0.4 + 0.6 * xs / w, 0.4 + 0.6 * ys / h])[..., None].astype(np.float32)


def _run(graph, scene_path, views: int, ao: np.ndarray) -> dict:
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(graph, scene_path=scene_path, size=SIZE, params={"views": str(views), "views.ipd": str(IPD)})
    result = execute_plan(plan, validate=True, frames=1, inputs={"ao": ao}, read_outputs=True)
    assert [m.text for m in result.messages] == []
    return result.outputs


@pytest.fixture(scope="module", params=sorted(GRAPHS))
def runs(request, tmp_path_factory):
    """(stereo outputs, [mono outputs of eye 0, eye 1], eye offsets, scene data of the centre camera)
    of the graph with forward_pbr's uniform light loop, or its clustered froxel lists."""
    graph = GRAPHS[request.param]
    from rgraph.scene.build import load_scene_data
    from rgraph.scene.instances import eye_offsets

    tmp_path = tmp_path_factory.mktemp("stereo_forward_post")
    centre = _scene(tmp_path, "centre")
    ao = _ao()
    stereo = _run(graph, centre, 2, ao)
    scene = load_scene_data(centre, SIZE)
    offsets = eye_offsets(scene, 0, 2, IPD)
    mono = [_run(graph, _scene(tmp_path, f"eye{k}", offsets[k]), 1, ao[k]) for k in range(2)]
    return stereo, mono, offsets, scene


@pytest.mark.parametrize("name", PER_EYE)
def test_stereo_layers_equal_mono_images_from_each_eye(runs, name):
    stereo, mono, _offsets, _scene_data = runs
    layers = np.asarray(stereo[name], dtype=np.float64)
    assert layers.shape == (2, SIZE[1], SIZE[0], layers.shape[-1])
    rtol, atol = TOLERANCE.get(name, DEFAULT_TOLERANCE)
    for eye in range(2):
        got, want = layers[eye], np.asarray(mono[eye][name], dtype=np.float64).reshape(layers[eye].shape)
        assert np.isfinite(got).all()
        bad = np.abs(got - want) > rtol * np.abs(want) + atol
        assert not bad.any(), (f"{name} eye {eye}: {int(bad.sum())} texels off, max diff "
                               f"{np.abs(got - want).max():.3g}, first at {np.argwhere(bad)[:4, :2].tolist()}")


@pytest.mark.parametrize("name", PER_EYE)
def test_the_eyes_see_different_pictures(runs, name):
    stereo, _mono, _offsets, _scene_data = runs
    layers = np.asarray(stereo[name], dtype=np.float64)
    threshold = 1e-3 if name == "depth" else 0.1
    assert np.abs(layers[0] - layers[1]).max() > threshold


def test_every_pass_has_work_in_both_eyes(runs):
    """The test has teeth: in each eye the decal covers pixels of the sphere, the SSS material
    is on screen, and a quarter of the pixels or more hold geometry."""
    stereo, _mono, offsets, scene = runs
    cam = scene.camera(0)
    w, h = SIZE
    px, py = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)
    (to_decal,) = scene.decal_matrices(cam.position)
    for eye in range(2):
        depth = np.asarray(stereo["depth"][eye][..., 0], dtype=np.float64)
        geometry = depth > 0
        assert geometry.sum() > w * h // 4
        # camera-relative (centre) world position of each pixel of this eye
        ndc = np.stack([px * 2 - 1, py * 2 - 1, depth, np.ones_like(depth)], axis=-1)
        world = ndc @ cam.inv_view_proj.T
        world = world[..., :3] / world[..., 3:4] + offsets[eye]
        local = np.concatenate([world, np.ones_like(depth)[..., None]], axis=-1) @ to_decal.T
        inside = geometry & np.all(np.abs(local[..., :3]) < 0.45, axis=-1)
        assert inside.sum() >= 4, f"eye {eye}: the decal covers {int(inside.sum())} pixels"
        sss = np.asarray(stereo["normal_sss"][eye][..., 3]) > 0.5
        assert sss.sum() >= 20, f"eye {eye}: {int(sss.sum())} SSS pixels"
    if "cluster_stats" in stereo:  # clustered: real lists (no froxel fell back to every light)
        from rgraph.passes.cluster_report import stats_of

        stats = stats_of(stereo["cluster_stats"])
        assert stats["overflowed_froxels"] == 0 and stats["references"] > 0, stats
