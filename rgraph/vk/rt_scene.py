"""The scene's geometry for acceleration structures: a BLAS per mesh (object-space float32
positions), an instance per placement with a camera-relative transform (translation = world
position - camera, formed in float64, so ray origins stay near 0 in large worlds). An
instance's custom index is its mesh's material index."""

from __future__ import annotations

import numpy as np

from rgraph.scene.camera import model_matrix
from rgraph.vk.errors import ExecutionError


def scene_data(plan: dict):
    """The plan's scene (``SceneData``) at the plan's size and camera."""
    from rgraph.scene.build import load_scene_data

    source = plan.get("scene_source")
    if not source:
        raise ExecutionError("an accel over the scene needs a scene (--scene)")
    return load_scene_data(source, tuple(plan.get("size") or (64, 64)), int(plan.get("camera", 0)))


def scene_geometry(plan: dict):
    from rgraph.vk.accel import Geometry

    data = scene_data(plan)
    cam = np.asarray(data.camera(0).position, dtype=np.float64)
    meshes = [(m.data.positions.astype(np.float32), m.data.indices.astype(np.uint32)) for m in data.meshes]
    instances = []
    for k, mesh in enumerate(data.meshes):
        for p in mesh.positions:
            m = model_matrix(p - cam, mesh.rotation, mesh.scale)
            instances.append((m[:3, :4].astype(np.float32), k, mesh.material))
    return Geometry(meshes, instances)
