"""The ray tracing scenes' camera presets see the scene from outside every object: a camera
inside a closed mesh (rt_gallery camera 4 was inside a wall the instance grid had centred on the
hall) sees coplanar inner faces, where raster and ray tracing legitimately pick different
surfaces, so the hybrid-vs-stand-alone comparison measures z-fighting instead of the renderer."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT

from rgraph.scene.build import load_scene_data
from rgraph.scene.camera import model_matrix

SCENES = ("rt_living_room", "rt_conference", "rt_gallery", "rt_tiny")


def _boxes(data):
    """World AABB (lo, hi) of every instance."""
    for mesh in data.meshes:
        local = np.asarray(mesh.data.positions, dtype=np.float64).reshape(-1, 3)
        for p in mesh.positions:
            m = model_matrix(np.asarray(p, dtype=np.float64), mesh.rotation, mesh.scale)
            world = local @ m[:3, :3].T + m[:3, 3]
            yield mesh.name, world.min(axis=0), world.max(axis=0)


@pytest.mark.parametrize("scene", SCENES)
def test_every_camera_preset_is_outside_every_object(scene):
    path = ROOT / "graphs" / "scenes" / f"{scene}.yaml"
    data = load_scene_data(path, (16, 9), 0)
    boxes = list(_boxes(data))
    for camera, preset in enumerate(data.model.cameras or [data.model.camera]):
        pos = np.asarray(preset.position, dtype=np.float64)
        inside = [name for name, lo, hi in boxes if (lo < pos).all() and (pos < hi).all()]
        assert not inside, f"{scene} camera {camera} at {pos.tolist()} is inside {inside}"
