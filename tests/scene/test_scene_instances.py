"""Scene additions of issue 18 (FORMAT.md 7): seeded instance counts, unique geometry, the
per-instance GPU table and the float64 frustum test (pure logic, no device)."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT

from rgraph.compiler.pipeline import frontend
from rgraph.scene.build import build_scene, load_scene_data
from rgraph.scene.instances import INSTANCE_BYTES, frustum_planes, instance_bytes, visible
from rgraph.spec.scene import SceneFile

SCENES = ROOT / "graphs" / "scenes"


def _scene(meshes: list[dict]) -> SceneFile:
    return SceneFile.model_validate({"scene": 1, "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]},
                                     "materials": {"m": {"base_color": [1, 1, 1]}}, "meshes": meshes})


def test_counted_instances_are_seeded_and_inside_their_bounds():
    mesh = {"shape": "box", "material": "m", "position": [1, 0, 0],
            "instances": {"count": 50, "seed": 4, "bounds": [[-2, 0, -3], [2, 1, 3]]}}
    a = build_scene(_scene([mesh])).meshes[0].positions
    b = build_scene(_scene([mesh])).meshes[0].positions
    assert a.shape == (50, 3) and np.array_equal(a, b)
    assert np.all(a >= [-1, 0, -3]) and np.all(a <= [3, 1, 3])
    other = build_scene(_scene([{**mesh, "instances": {**mesh["instances"], "seed": 5}}])).meshes[0].positions
    assert not np.array_equal(a, other)


def test_unique_instances_get_their_own_geometry():
    data = build_scene(_scene([{"shape": "box", "material": "m", "unique": True,
                                "instances": {"grid": [3, 1, 2], "spacing": 2}}]))
    assert len(data.meshes) == 6 and data.draw_count == 6
    sizes = [np.ptp(m.data.positions, axis=0) for m in data.meshes]
    assert len({tuple(np.round(s, 9)) for s in sizes}) == 6
    assert all(0.6 - 1e-9 <= s.min() and s.max() <= 1.4 + 1e-9 for s in sizes)
    assert [m.first_draw for m in data.meshes] == list(range(6))
    n = data.meshes[0].data.normals
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)


def test_the_vr_scenes_have_the_studys_object_counts():
    assert load_scene_data(SCENES / "vr_instanced.yaml").draw_count == 32768
    unique = load_scene_data(SCENES / "vr_unique.yaml")
    assert sum(1 for m in unique.meshes if m.name.startswith("0:box#")) == 4096
    assert frontend("clustered", SCENES / "vr_unique.yaml").spec.resources["draw_args"].bytes == 16 + 4097 * 28 + 1024


def test_instance_table_holds_float64_translations_and_ids():
    far = 1.0e7 + 0.123456789
    data = build_scene(_scene([{"shape": "sphere", "params": {"radius": 0.5}, "material": "m", "position": [far, 2, 0]}]))
    raw = instance_bytes(data)
    assert len(raw) == INSTANCE_BYTES
    doubles = np.frombuffer(raw[:32], dtype=np.float64)
    assert doubles[0] == far and doubles[1] == 2.0
    f = np.frombuffer(raw, dtype=np.float32)
    assert float(f[36]) + float(f[40]) == pytest.approx(far, abs=1e-6)  # hi + lo
    assert f[47] == pytest.approx(np.sqrt(3) * 0.5, rel=1e-5)  # the sphere around its bounding box


def test_frustum_test_keeps_what_is_in_front_and_culls_what_is_behind():
    mesh = {"shape": "sphere", "params": {"radius": 0.5}, "material": "m",
            "instances": {"grid": [1, 1, 3], "spacing": 10}}  # z = -10, 0, 10; camera at z=5 looking at -z
    data = build_scene(_scene([mesh]))
    cam = data.camera(0)
    mask = visible(data, cam.position, [cam.view_proj])
    assert mask.tolist() == [True, True, False]
    planes = frustum_planes(cam.view_proj)
    assert planes.shape == (5, 4)
