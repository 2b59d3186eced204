"""CPU packing mirrors shaders/scene/scene.glsl: block sizes from SPIR-V reflection, values in place."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT

from rgraph.scene import packing
from rgraph.scene.build import load_scene_data

ROOT = ROOT
CCT = ROOT / "graphs" / "scenes" / "cct.yaml"


def test_reflected_block_sizes_match_packing():
    from rgraph.vk.shaders import compile_shader, find_shader

    compiled = compile_shader(find_shader("scene/tests/layout_probe.comp"))
    sizes = {(b.set, b.binding): b.block_bytes for b in compiled.reflection.bindings}
    assert sizes[(0, 0)] == packing.FRAME_BYTES
    assert sizes[(2, 0)] == 2 * packing.DRAW_BYTES
    assert sizes[(2, 1)] == 2 * packing.MATERIAL_BYTES
    assert sizes[(2, 2)] == 2 * packing.SCENE_LIGHT_BYTES
    assert sizes[(2, 3)] == 2 * packing.DECAL_BYTES
    assert sizes[(2, 4)] == 2 * packing.LIGHT_BYTES


def test_offsets_written_in_scene_glsl_match_packing():
    text = (ROOT / "shaders" / "scene" / "scene.glsl").read_text()
    block = text[text.index("uniform Frame {"):text.index("} frame;")]
    for name, offset in packing.FRAME_OFFSETS.items():
        line = next(ln for ln in block.splitlines() if f" {name};" in ln or f" {name}[" in ln)
        assert f"// {offset:>3}" in line or f"//  {offset}" in line or f"// {offset} " in line, (name, line)


def test_frame_and_tables_hold_the_scene():
    scene = load_scene_data(CCT, (64, 48))
    frame = np.frombuffer(packing.frame_bytes(scene, 5), dtype=np.float32)
    ints = frame.view(np.int32)
    cam = scene.camera(5)
    o = packing.FRAME_OFFSETS
    vp = frame[o["view_proj"] // 4:o["view_proj"] // 4 + 16].reshape(4, 4).T  # column-major
    np.testing.assert_allclose(vp, cam.view_proj, rtol=1e-6, atol=1e-6)
    assert list(ints[o["counts"] // 4:o["counts"] // 4 + 4]) == [4, 2, len(scene.decals), 2]
    assert ints[o["counts2"] // 4 + 1] == scene.draw_count
    np.testing.assert_allclose(frame[o["viewport"] // 4:o["viewport"] // 4 + 4], [64, 48, 1 / 64, 1 / 48])
    np.testing.assert_allclose(frame[o["time"] // 4:o["time"] // 4 + 2], [5 / 60, 5])
    hi, lo = frame[o["camera_hi"] // 4:o["camera_hi"] // 4 + 3], frame[o["camera_lo"] // 4:o["camera_lo"] // 4 + 3]
    np.testing.assert_allclose(hi.astype(np.float64) + lo, cam.position, rtol=1e-12)
    draws = np.frombuffer(packing.draws_bytes(scene, 0), dtype=np.float32).reshape(-1, packing.DRAW_BYTES // 4)
    assert len(draws) == scene.draw_count
    models = scene.draw_models(cam.position)
    for k, (model, normal, material, mesh, flags) in enumerate(models):
        np.testing.assert_allclose(draws[k, :16].reshape(4, 4).T, model, rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(draws[k, 16:32].reshape(4, 4).T, normal, rtol=1e-5, atol=1e-6)
        assert list(draws[k].view(np.uint32)[32:35]) == [material, mesh, flags]
    assert len(packing.materials_bytes(scene)) == len(scene.materials) * packing.MATERIAL_BYTES
    lights = np.frombuffer(packing.scene_lights_bytes(scene), dtype=np.float32).reshape(-1, 16)
    assert list(lights[:, 3]) == [0, 0, 1, 1] and list(lights[:, 11]) == [0, 1, -1, -1]
    decals = np.frombuffer(packing.decals_bytes(scene, 0), dtype=np.float32).reshape(-1, packing.DECAL_BYTES // 4)
    assert len(decals) == len(scene.decals)
    # a decal's centre maps to the box centre
    centre = np.append(scene.decals[0].position - cam.position, 1.0)
    np.testing.assert_allclose((decals[0, :16].reshape(4, 4).T @ centre)[:3], 0, atol=1e-4)


@pytest.mark.parametrize("value", [0.0, 1.0, 123456.789, 1e8 + 0.25, -3.3e11, 1e12 + 1e-3])
def test_hi_lo_split_restores_float64(value):
    hi, lo = packing.split_hi_lo(np.array([value]))
    assert abs(float(hi[0]) + float(lo[0]) - value) <= abs(value) * 2.0 ** -46 + 1e-30


def test_vectorized_draws_equal_the_per_draw_float64_construction():
    """draws_bytes caches world matrices and subtracts the camera in float64 for all draws at
    once; it must give the same bytes as building each camera-relative matrix on its own."""
    import numpy as np

    from rgraph.scene import packing
    from rgraph.scene.build import build_scene
    from rgraph.spec.scene import load_scene

    scene = build_scene(load_scene("graphs/scenes/cct.yaml").model, (64, 36))
    draws = scene.draw_models(scene.camera(0).position)
    want = np.zeros((len(draws), packing.DRAW_BYTES // 4), dtype=np.float32)
    for k, (model, normal, material, mesh, flags) in enumerate(draws):
        want[k, 0:16] = packing.mat(model)
        want[k, 16:32] = packing.mat(normal)
        want.view(np.uint32)[k, 32:36] = (material, mesh, flags, 0)
    assert packing.draws_bytes(scene, 0) == want.tobytes()
    assert packing.draws_bytes(scene, 7) == want.tobytes()  # static camera: the same every frame
