"""forward_pbr end to end on lavapipe: light_setup + shadow + depth_prepass + IBL + forward on the
cct scenes (tests/pass_graphs/forward*.yaml), under validation.

Checks: zero validation messages; every output finite; diffuse/specular non-zero wherever the
depth prepass left geometry; normal_sss holds unit camera-facing normals and the material's
SSS strength; the diffuse output against a float64 per-pixel reference (passes/forward_ref.py:
Lambert over every light of light_setup_reference, IBL diffuse from the reference prefiltered
environment, ambient, AO) on interior pixels of cct_no_shadows, with the GPU's own depth and
8-bit normal as the reference's position and normal; with shadows (cct) the diffuse never
exceeds the unshadowed reference and is visibly lower somewhere; the AO path (imported ao)
against the no-AO graph (HBAO culled: screen AO = 1).

Tolerance of the diffuse reference: |gpu - ref| <= 0.03 * |ref| + 0.01 (the reference takes
the normal from the r8g8b8a8 normal_sss, ~2e-3 rad quantization, and float16 storage).
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT, TESTS
from rgraph.passes import forward_ref as ref
from rgraph.passes import ibl_ref

from rgraph.compiler.pipeline import compile_graph

GRAPHS = TESTS / "pass_graphs"
SCENES = ROOT / "graphs" / "scenes"
SIZE = (64, 48)
AO_VALUE = 0.5
RTOL, ATOL = 0.03, 0.01


def run(graph: str, scene: str | None = None, ao: float | None = AO_VALUE, frames: int = 2,
        params: dict[str, str] | None = None):
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / graph, scene_path=SCENES / scene if scene else None, size=SIZE,
                         params=params or {})
    inputs = {"ao": np.full((SIZE[1], SIZE[0], 1), ao, np.float32)} if ao is not None else {}
    result = execute_plan(plan, validate=True, frames=frames, inputs=inputs, read_outputs=True)
    return plan, result


def bilinear_equirect(level: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Bilinear, clamp-to-edge lookup of an equirect level (h, w, 3) along unit ``dirs`` (..., 3)."""
    h, w = level.shape[:2]
    uv = ibl_ref.equirect_uv(dirs)
    x = np.clip(uv[..., 0] * w - 0.5, 0, w - 1)
    y = np.clip(uv[..., 1] * h - 0.5, 0, h - 1)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    top = level[y0, x0] * (1 - fx) + level[y0, x1] * fx
    bottom = level[y1, x0] * (1 - fx) + level[y1, x1] * fx
    return top * (1 - fy) + bottom * fy


def diffuse_reference(plan: dict, outputs: dict, screen_ao: float, *, shadows: bool = False):
    """(reference diffuse (h, w, 3), interior mask): Lambert + IBL diffuse + ambient per pixel."""
    from rgraph.passes.scene_ref import depth_prepass_reference, light_setup_reference

    from rgraph.scene.build import load_scene_data
    from rgraph.scene.packing import AMBIENT

    scene = load_scene_data(plan["scene_source"], SIZE)
    cam = scene.camera(0)
    ref_depth, owner = depth_prepass_reference(scene, 0)
    depth = outputs["depth"][..., 0].astype(np.float64)
    w, h = SIZE
    # interior: the same draw in the 3x3 neighbourhood and the GPU depth agrees with the reference
    pad = np.pad(owner, 1, constant_values=-2)
    same = np.all([pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] == owner for dy in (-1, 0, 1) for dx in (-1, 0, 1)],
                  axis=0)
    interior = same & (owner >= 0) & (np.abs(depth - ref_depth) <= 1e-4 * np.maximum(ref_depth, 1e-6))
    # camera-relative world position from the GPU depth, normal from normal_sss
    px, py = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)
    ndc = np.stack([px * 2 - 1, py * 2 - 1, depth, np.ones_like(depth)], axis=-1)
    world = ndc @ cam.inv_view_proj.T
    world = world[..., :3] / world[..., 3:4]
    normal = outputs["normal_sss"][..., :3].astype(np.float64) * 2 - 1
    normal /= np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-12)
    models = scene.draw_models(cam.position)
    material_of = np.array([m[2] for m in models])
    mats = [scene.materials[k] for k in material_of[np.maximum(owner, 0)].ravel()]
    base = np.array([m.base_color for m in mats]).reshape(h, w, 3)
    metallic = np.array([m.metallic for m in mats]).reshape(h, w)
    rough = np.array([m.roughness for m in mats]).reshape(h, w)
    baked = np.array([m.baked_ao for m in mats]).reshape(h, w)
    s = ref.make_surface(normal, -world, normal, base, rough, metallic)
    total = np.zeros((h, w, 3))
    lights = light_setup_reference(scene, 0)
    for li in lights:
        if int(round(li[7])) == 0:  # directional
            ldir = np.broadcast_to(li[4:7], world.shape)
            radiance = np.broadcast_to(li[8:11], world.shape)
        else:
            d = li[0:3] - world
            dist2 = np.sum(d * d, axis=-1)
            x = dist2 * li[15]
            falloff = np.clip(1 - x * x, 0, 1) ** 2 / np.maximum(dist2, 1e-6)
            ldir = ref.safe_normalize(d, s["n"])
            radiance = li[8:11] * falloff[..., None]
        diff, _spec = ref.eval_light(s, ldir, radiance)
        total += diff
    params = plan["params"]
    width, mips, samples = int(params["ibl.env_width"]), int(params["ibl.env_mips"]), int(params["ibl.samples"])
    top = ibl_ref.prefilter(max(1, width >> (mips - 1)), max(1, (width // 2) >> (mips - 1)), 1.0, samples)
    irradiance = bilinear_equirect(top, s["n"]) * float(params["forward.ibl_intensity"]) + np.asarray(AMBIENT)
    ao = ref.combine_ao(np.full((h, w), screen_ao), baked, int(params["forward.ao_combine"]))
    total += s["diffuse_color"] * irradiance * ao[..., None]
    return ref.hdr_clamp(total), interior


def check_common(result):
    assert [m.text for m in result.messages] == []
    out = result.outputs
    for name in ("diffuse", "specular", "normal_sss", "depth"):
        assert np.isfinite(out[name]).all(), name
    geometry = out["depth"][..., 0] > 0
    assert geometry.mean() > 0.5  # the cct camera sees the neck and the drape behind it
    non_metal = out["diffuse"][..., :3].sum(-1) > 0
    assert np.all(out["specular"][..., :3].sum(-1)[geometry] > 0)
    assert non_metal[geometry].mean() > 0.9  # only the steel scalpel has no diffuse
    assert np.all(out["diffuse"][~geometry] == 0) and np.all(out["specular"][~geometry] == 0)
    n = out["normal_sss"][..., :3] * 2 - 1
    length = np.linalg.norm(n, axis=-1)[geometry]
    assert np.all(np.abs(length - 1) < 0.02)
    sss = np.round(out["normal_sss"][..., 3][geometry] * 255) / 255
    assert np.any(np.abs(sss - 0.8) < 0.003)  # skin
    assert np.any(sss == 0.0)  # the drape, steel, tube


@pytest.mark.vulkan
def test_forward_unshadowed_diffuse_matches_reference():
    plan, result = run("forward.yaml", "cct_no_shadows.yaml", frames=1)  # frame 0: the reference's deformation
    assert not any(a["resource"] == "shadow_maps" for p in plan["passes"] if p["name"] == "forward"
                   for a in p["accesses"])  # the shadow pass is culled: no shadow lights
    check_common(result)
    want, interior = diffuse_reference(plan, result.outputs, AO_VALUE)
    got = result.outputs["diffuse"][..., :3]
    assert interior.mean() > 0.7
    err = np.abs(got - want) - (RTOL * np.abs(want) + ATOL)
    assert err[interior].max() <= 0, f"worst excess {err[interior].max()}"


@pytest.mark.vulkan
def test_forward_with_shadows_and_without_ao():
    plan, result = run("forward.yaml", None, frames=2)
    check_common(result)
    unshadowed, interior = diffuse_reference(plan, result.outputs, AO_VALUE)
    got = result.outputs["diffuse"][..., :3].astype(np.float64)
    assert np.all((got - unshadowed)[interior] <= RTOL * unshadowed[interior] + ATOL)
    darker = (unshadowed - got).sum(-1) > 0.1 * unshadowed.sum(-1)
    assert darker[interior].mean() > 0.02  # the lamps cast shadows (the neck on the drape, the tube)
    # HBAO culled: the same frame with screen AO 1 (nothing else changes: min(1, baked) = baked)
    plan2, result2 = run("forward_noao.yaml", None, ao=None, frames=2)  # the same frame (the neck breathes)
    check_common(result2)
    assert "ao" not in [a["resource"] for p in plan2["passes"] if p["name"] == "forward" for a in p["accesses"]]
    no_ao = result2.outputs["diffuse"][..., :3].astype(np.float64)
    ref_ao, _ = diffuse_reference(plan, result.outputs, AO_VALUE)
    ref_no_ao, _ = diffuse_reference(plan2, result2.outputs, 1.0)
    gained = (no_ao - got)[interior]
    want_gain = (ref_no_ao - ref_ao)[interior]
    assert np.all(want_gain >= 0) and want_gain.max() > 0.01
    assert np.all(np.abs(gained - want_gain) <= RTOL * np.abs(want_gain) + ATOL)
    spec_ao, spec_no_ao = result.outputs["specular"][..., :3], result2.outputs["specular"][..., :3]
    assert np.all(spec_no_ao >= spec_ao - 1e-3) and np.any(spec_no_ao > spec_ao + 1e-3)  # specular occlusion
