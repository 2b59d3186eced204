"""Scene build from scene files: counts, bundled cct variants, deformation, large worlds."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT

from rgraph.scene import packing
from rgraph.scene.build import build_scene, load_scene_data
from rgraph.scene.deform import Deformer
from rgraph.scene.large_world import DISTANCES, study
from rgraph.scene.shapes import MeshData, make_shape
from rgraph.spec.scene import load_scene

SCENES = ROOT / "graphs" / "scenes"


def test_cct_is_the_scene_issue_5_describes():
    scene = load_scene(SCENES / "cct.yaml")
    f = scene.features
    assert f["shadow_lights"] == 2 and f["point_lights"] >= 2 and f["decals"] >= 3
    assert f["sss_materials"] >= 2 and f["deformable_meshes"] == 1 and f["reflective_materials"] >= 1
    shapes = {m.shape for m in scene.model.meshes}
    assert {"neck", "torus", "tube", "blob", "box", "capsule"} <= shapes
    skin = next(m for m in scene.model.meshes if m.deformable)
    assert scene.model.materials[skin.material].sss > 0
    data = load_scene_data(SCENES / "cct.yaml", (64, 48))
    assert data.draw_count == len(scene.model.meshes) and len(data.shadow_lights) == 2
    # the camera sees the incision: the decals' centres project inside the frame
    cam = data.camera(0)
    for d in data.decals:
        c = cam.view_proj @ np.append(d.position - cam.position, 1)
        assert np.all(np.abs(c[:2] / c[3]) < 1) and 0 < c[2] / c[3] <= 1


@pytest.mark.parametrize("variant,feature", [("cct_no_sss", "sss_materials"), ("cct_no_decals", "decals"),
                                             ("cct_no_shadows", "shadow_lights")])
def test_variants_differ_only_in_their_missing_effect(variant, feature):
    base, other = load_scene(SCENES / "cct.yaml"), load_scene(SCENES / f"{variant}.yaml")
    assert other.features[feature] == 0 and base.features[feature] > 0
    assert {k: v for k, v in other.features.items() if k != feature} == \
           {k: v for k, v in base.features.items() if k != feature}
    a, b = base.model.model_dump(), other.model.model_dump()
    a.pop("name"), b.pop("name")
    if feature == "sss_materials":
        for m in a["materials"].values():
            m["sss"] = 0.0
    elif feature == "decals":
        a["decals"] = []
    else:
        for light in a["lights"]:
            light["shadows"] = False
    assert a == b


def test_deformable_mesh_moves_every_frame_with_unit_normals():
    data = load_scene_data(SCENES / "cct.yaml", (32, 24))
    (mesh,) = data.deformable
    frames = [data.deformed(mesh, f) for f in (0, 1, 30, 61)]
    for a, b in zip(frames, frames[1:], strict=False):
        assert np.abs(a.positions - b.positions).max() > 1e-7
    for m in frames:
        assert np.isfinite(m.normals).all()
        np.testing.assert_allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-12)
    # the press dents the skin inwards (along -normal) near its centre, most at half a period
    d = mesh.deformer
    t = d.press_period / 2
    no_press = Deformer(d.rest, press_depth=0.0).positions(t)
    inward = np.einsum("ij,ij->i", no_press - d.positions(t), d.rest.normals)
    assert inward.min() > -1e-15
    assert inward.max() == pytest.approx(0.1 * d.press_depth * d._radius, rel=0.05)
    assert np.abs(Deformer(d.rest, press_depth=0.0).positions(0.0) - d.positions(0.0)).max() < 1e-15
    # the per-frame vertex bytes are the deformed vertices
    raw = np.frombuffer(packing.vertex_bytes(frames[2]), dtype=np.float32).reshape(-1, 6)
    np.testing.assert_allclose(raw[:, :3], frames[2].positions, rtol=1e-6, atol=1e-7)


def test_deformation_with_zero_area_triangles_stays_finite():
    base = make_shape("sphere", {"radius": 1.0, "segments": 8, "rings": 4})
    # append a zero-area triangle (three copies of one point) and a sliver collapsing under the press
    extra = np.array([[0, 0, 1.0]] * 3)
    pos = np.concatenate([base.positions, extra])
    nrm = np.concatenate([base.normals, np.tile([0, 0, 1.0], (3, 1))])
    n = len(base.positions)
    idx = np.concatenate([base.indices, np.array([[n, n + 1, n + 2]], dtype=np.uint32)])
    d = Deformer(MeshData(pos, nrm, idx))
    for t in (0.0, 0.3, 0.85, 2.0):
        m = d.at(t)
        assert np.isfinite(m.normals).all()
        np.testing.assert_allclose(np.linalg.norm(m.normals, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(d.at(0.3).normals[n:], nrm[n:])  # fallback: the rest normal


def test_camera_relative_draws_do_not_depend_on_world_offset():
    scene = load_scene(SCENES / "cct.yaml").model
    near = build_scene(scene, (64, 48))
    for offset in (1e6, 1e8, 1e10):
        moved = scene.model_copy(update={
            "camera": scene.camera.model_copy(update={
                "position": list(np.add(scene.camera.position, offset)),
                "look_at": list(np.add(scene.camera.look_at, offset))}),
            "meshes": [m.model_copy(update={"position": list(np.add(m.position, offset))}) for m in scene.meshes],
        })
        far = build_scene(moved, (64, 48))
        a = np.frombuffer(packing.draws_bytes(near, 3), dtype=np.float32)
        b = np.frombuffer(packing.draws_bytes(far, 3), dtype=np.float32)
        # translations are (position - camera) in float64: exact for these offsets up to float64
        # spacing at the offset (1e10: 2e-6 m)
        np.testing.assert_allclose(b, a, atol=4e-6 * max(1.0, offset / 1e10), rtol=1e-6)


def test_large_world_study_camera_relative_stays_sub_hundredth_pixel():
    rows = study(DISTANCES, width=1920, height=1080)
    assert [r.distance for r in rows] == list(DISTANCES)
    for r in rows:
        assert r.relative_px < 0.01, r
    naive = [r.naive_px for r in rows]
    assert naive[0] > 1.0  # already several pixels off at 10 km
    assert all(b >= a for a, b in zip(naive, naive[1:], strict=False))  # and it only grows
    assert naive[-1] == np.inf or naive[-1] > 1e3
    assert rows[-1].naive64_px > 0.1  # even float64 world matrices drift at 1e12 m
