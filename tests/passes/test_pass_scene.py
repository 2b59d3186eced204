"""Scene passes on lavapipe (light_setup, shadow_map, depth_prepass) vs their NumPy references.

Tolerances: depth 1e-5 relative on pixels whose 3x3 neighbourhood shows one draw (float32
transforms of float64 matrices; measured ~4e-7); silhouette coverage may differ on at most
2% of covered pixels (rasterization rules); shadow depth 1e-5 absolute without bias;
lights 1e-6 relative to the distance from the camera (+1e-6).
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT, TESTS
from rgraph.passes import scene_ref
from ruamel.yaml import YAML

from rgraph.compiler.pipeline import compile_graph
from rgraph.scene.build import load_scene_data
from rgraph.scene.packing import unpack_lights

GRAPHS = TESTS / "pass_graphs"
GRAPH = GRAPHS / "scene_passes.yaml"
SCENE = GRAPHS / "scene_simple_scene.yaml"
ROOT = ROOT
W, H, SHADOW = 48, 32, 64
NO_BIAS = {"shadow.bias_constant": "0", "shadow.bias_slope": "0", "shadow.size": str(SHADOW)}

pytestmark = pytest.mark.vulkan


def run(frames=3, params=None, scene=None, size=(W, H)):
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPH, scene_path=scene, size=size, params=params or NO_BIAS)
    result = execute_plan(plan, validate=True, frames=frames, read_outputs=True)
    assert [m.text for m in result.messages] == []
    for name, out in result.outputs.items():
        if out.dtype != np.uint8:
            assert np.isfinite(out).all(), name
    return result


def same_owner(owner: np.ndarray) -> np.ndarray:
    """Pixels whose 3x3 neighbourhood belongs to one draw (no silhouette or boundary)."""
    h, w = owner.shape
    padded = np.pad(owner, 1, constant_values=-2)
    ok = owner >= 0
    for dy in range(3):
        for dx in range(3):
            ok &= padded[dy:dy + h, dx:dx + w] == owner
    return ok


def check_depth(gpu, ref, owner, rtol=1e-5):
    covered = (ref > 0).sum()
    assert covered > 0.2 * ref.size  # the scene fills a good part of the frame
    assert ((gpu > 0) != (ref > 0)).sum() <= 0.02 * covered
    m = same_owner(owner) & (gpu > 0)
    assert m.sum() > 0.5 * covered
    err = np.abs(gpu - ref)[m] / ref[m]
    assert err.max() <= rtol, err.max()


def write_scene(tmp_path, edit, name="scene.yaml"):
    yaml = YAML()
    data = yaml.load(SCENE.read_text())
    edit(data)
    path = tmp_path / name
    with path.open("w") as fh:
        yaml.dump(data, fh)
    return path


def test_depth_shadow_and_lights_match_references():
    result = run(frames=3)
    scene = load_scene_data(SCENE, (W, H))
    ref, owner = scene_ref.depth_prepass_reference(scene, 2)
    check_depth(result.outputs["depth"][..., 0], ref, owner)
    shadows = result.outputs["shadow_maps"]
    assert shadows.shape == (2, SHADOW, SHADOW, 1)
    for layer in range(2):
        sref, sowner = scene_ref.shadow_map_reference(scene, 2, layer, SHADOW)
        got = shadows[layer, ..., 0]
        assert ((got > 0) != (sref > 0)).sum() <= 0.02 * (sref > 0).sum()
        m = same_owner(sowner) & (got > 0)
        assert np.abs(got - sref)[m].max() <= 1e-5
    lights = unpack_lights(result.outputs["lights"].tobytes(), 4)
    want = scene_ref.light_setup_reference(scene, 2)
    tol = 1e-6 * (1 + np.linalg.norm(want[:, :3], axis=1, keepdims=True))
    assert np.all(np.abs(lights - want) <= tol)


def test_default_shadow_bias_pushes_stored_depth_away_from_the_light():
    result = run(frames=1, params={"shadow.size": str(SHADOW)})
    scene = load_scene_data(SCENE, (W, H))
    sref, sowner = scene_ref.shadow_map_reference(scene, 0, 0, SHADOW)
    got = result.outputs["shadow_maps"][0, ..., 0]
    m = same_owner(sowner) & (got > 0)
    diff = sref - got
    assert diff[m].min() > 0  # every stored depth lies behind the surface (seen from the light)
    # ... by the slope-scaled bias (1.5 x the depth change per texel), not by a different surface
    padded = np.pad(sref, 1, mode="edge")
    slope = np.max([np.abs(padded[1 + dy:1 + dy + SHADOW, 1 + dx:1 + dx + SHADOW] - sref)
                    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0))], axis=0)
    assert np.all(diff[m] <= 1.5 * 1.25 * slope[m] + 1e-6)


def test_light_parallel_to_up_casts_finite_shadows(tmp_path):
    def straight_down(d):
        d["lights"][0]["direction"] = [0, -1, 0]
        d["lights"][1]["direction"] = [0, 1e-9, 0.0]  # upwards, numerically parallel too
        d["lights"][1]["direction"][1] = 1.0
    path = write_scene(tmp_path, straight_down)
    result = run(frames=1, scene=path)
    scene = load_scene_data(path, (W, H))
    for layer in range(2):
        sref, sowner = scene_ref.shadow_map_reference(scene, 0, layer, SHADOW)
        got = result.outputs["shadow_maps"][layer, ..., 0]
        assert np.isfinite(got).all() and (got > 0).sum() > 0.3 * got.size  # the ground plane fills it
        m = same_owner(sowner) & (got > 0)
        assert np.abs(got - sref)[m].max() <= 1e-5


def test_deformable_mesh_changes_between_frames_on_the_gpu():
    scene = load_scene_data(SCENE, (W, H))
    first, later = run(frames=1), run(frames=20)
    d0, d1 = first.outputs["depth"][..., 0], later.outputs["depth"][..., 0]
    ref0, own0 = scene_ref.depth_prepass_reference(scene, 0)
    ref1, own1 = scene_ref.depth_prepass_reference(scene, 19)
    check_depth(d0, ref0, own0)
    check_depth(d1, ref1, own1)
    torus = next(m for m in scene.meshes if m.deformer is not None).first_draw
    moved = (own0 == torus) | (own1 == torus)
    assert np.abs(d0 - d1)[moved].max() > 1e-5
    assert np.abs(d0 - d1)[~moved & (own0 >= 0) & (own1 >= 0)].max() == 0  # rigid meshes stay put


@pytest.mark.parametrize("offset", [1e6, 1e9])
def test_large_world_renders_like_the_origin(tmp_path, offset):
    def shift(d):
        for key in ("position", "look_at"):
            d["camera"][key] = [float(x) + offset for x in d["camera"][key]]
        for item in list(d["meshes"]) + list(d["decals"]) + [li for li in d["lights"] if "position" in li]:
            item["position"] = [float(x) + offset for x in item.get("position", [0, 0, 0])]
    path = write_scene(tmp_path, shift)
    near, far = run(frames=1), run(frames=1, scene=path)
    scene = load_scene_data(path, (W, H))
    ref, owner = scene_ref.depth_prepass_reference(scene, 0)
    check_depth(far.outputs["depth"][..., 0], ref, owner)
    a, b = near.outputs["depth"][..., 0], far.outputs["depth"][..., 0]
    m = same_owner(owner) & (a > 0) & (b > 0)
    assert (np.abs(a - b)[m] / a[m]).max() < 1e-5
    la = unpack_lights(near.outputs["lights"].tobytes(), 4)
    lb = unpack_lights(far.outputs["lights"].tobytes(), 4)
    np.testing.assert_allclose(lb, la, atol=2e-6)  # hi/lo light positions survive the offset


def test_surgery_with_cct_runs_clean_with_the_scene_passes():
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(ROOT / "graphs" / "surgery.yaml", scene_path=ROOT / "graphs" / "scenes" / "cct.yaml",
                         size=(48, 32), params={"shadow.size": "64"})
    impls = {"light_setup": "light_setup", "shadow": "shadow_map", "depth_prepass": "depth_prepass"}
    for p in plan["passes"]:
        if p["name"] in impls and not p.get("impl"):
            p["impl"] = impls[p["name"]]
    result = execute_plan(plan, validate=True, frames=2)
    assert [m.text for m in result.messages] == []


def test_missing_output_layer_feature_is_a_clear_error():
    from types import SimpleNamespace

    from rgraph.impl import lookup
    from rgraph.vk.errors import ExecutionError

    setup = SimpleNamespace(name="shadow", device=SimpleNamespace(enabled_features={"synchronization2"}))
    with pytest.raises(ExecutionError, match="shaderOutputLayer"):
        lookup("shadow_map")(setup)
