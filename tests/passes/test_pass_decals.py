"""Deferred decals (``decals``) against the NumPy float64 reference on a scene of our own.

Tolerance: 2e-3 absolute + 2e-3 relative on diffuse and specular (fp16 targets, float32
matrices), except on pixels within 1e-4 (box units) of a decal's x/y faces, where float32
and float64 may disagree about inside/outside (reported by the reference as ``edge``).
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rgraph.passes import decals_ref as ref
from rgraph.passes.screenspace_ref import Camera, render_depth

from rgraph.compiler.pipeline import compile_graph

GRAPHS = TESTS / "pass_graphs"
SCENE = GRAPHS / "decals_scene.yaml"
SPHERE = ((0.03, 0.0, 0.015), 0.02)  # world (= camera-relative + (0, 0, 0.3)) centre, radius


def scene_inputs(w: int, h: int):
    """Depth of the z = 0 plane and a sphere seen by the scene's camera, their normals, colours."""
    cam = Camera(fov_y=30, near=0.01, aspect=w / h)  # view space = world - (0, 0, 0.3)
    centre = np.array(SPHERE[0]) - (0, 0, 0.3)
    depth = render_depth(w, h, cam, planes=[((0, 0, -0.3), (0, 0, 1))], spheres=[(centre, SPHERE[1])])
    depth[: h // 8] = 0.0  # a band of sky
    depth = depth.astype(np.float32).astype(np.float64)
    z = np.where(depth > 0, cam.near / np.where(depth > 0, depth, 1), 0)
    ys, xs = np.mgrid[0:h, 0:w]
    ndc_x, ndc_y = 2 * (xs + 0.5) / w - 1, 2 * (ys + 0.5) / h - 1
    pos = np.stack([ndc_x * z / cam.p00, ndc_y * z / cam.p11, -z], axis=-1)
    on_sphere = np.abs(np.linalg.norm(pos - centre, axis=-1) - SPHERE[1]) < 1e-3
    n = np.where(on_sphere[..., None], (pos - centre) / SPHERE[1], [0.0, 0.0, 1.0])
    nsss = np.zeros((h, w, 4))
    nsss[..., :3] = np.round((0.5 * n + 0.5) * 255) / 255
    nsss[..., 3] = 0.8
    rng = np.random.default_rng(3)
    diffuse = np.float16(rng.uniform(0, 1, (h, w, 4))).astype(np.float64)
    specular = np.float16(rng.uniform(0, 1, (h, w, 4))).astype(np.float64)
    return depth, nsss, diffuse, specular


def expected(depth, nsss, diffuse, specular, size):
    from rgraph.scene.build import LIGHT_TYPES, load_scene_data

    data = load_scene_data(SCENE, size)
    cam = data.camera(0)
    boxes = [ref.DecalBox(m, (*d.material.base_color, d.material.opacity))
             for d, m in zip(data.decals, data.decal_matrices(cam.position), strict=True)]
    sun = next(li for li in data.lights if li.type == LIGHT_TYPES["directional"])
    from rgraph.scene.build import AMBIENT

    return ref.reference(depth, nsss, diffuse, specular, inv_view_proj=cam.inv_view_proj, decals=boxes,
                         to_sun=-np.asarray(sun.direction), sun_radiance=np.asarray(sun.radiance), ambient=AMBIENT)


def test_reference_covers_what_the_boxes_cover():
    w, h = 64, 48
    depth, nsss, diffuse, specular = scene_inputs(w, h)
    out = expected(depth, nsss, diffuse, specular, (w, h))
    cov = out["coverage"]
    assert np.all(cov[depth == 0] == 0)  # nothing on the sky
    assert 0.02 < np.mean(cov > 0) < 0.5  # the decals cover part of the image
    assert cov.max() > 0.9  # the overlap of blood (0.92) and ink (0.6): 1 - 0.08 * 0.4
    untouched = cov == 0
    assert np.array_equal(out["diffuse"][untouched], diffuse[untouched])
    assert np.array_equal(out["specular"][untouched], specular[untouched])
    # blood over the plane at full coverage: the specular below is hidden by 92 %
    full = np.isclose(cov, 0.92)
    assert full.any()
    np.testing.assert_allclose(out["specular"][full][:, :3], 0.08 * specular[full][:, :3], rtol=1e-12)


@pytest.mark.vulkan
def test_decals_match_reference():
    from rgraph.vk.executor import execute_plan

    w, h = 64, 48
    depth, nsss, diffuse, specular = scene_inputs(w, h)
    plan = compile_graph(GRAPHS / "decals.yaml", size=(w, h))
    result = execute_plan(plan, validate=True, read_outputs=True, inputs={
        "depth": depth[..., None], "normal_sss": nsss, "diffuse": diffuse, "specular": specular})
    assert [m.text for m in result.messages] == []
    want = expected(depth, nsss, diffuse, specular, (w, h))
    ok = ~want["edge"]
    assert ok.mean() > 0.95
    for name in ("diffuse", "specular"):
        got = np.asarray(result.outputs[name], np.float64)
        assert np.all(np.isfinite(got))
        err = np.abs(got - want[name]) - (2e-3 + 2e-3 * np.abs(want[name]))
        assert err[ok].max() <= 0, f"{name}: worst excess {err[ok].max()}"
    assert np.array_equal(np.asarray(result.outputs["diffuse"], np.float64)[want["coverage"] == 0],
                          diffuse[want["coverage"] == 0])
