"""NumPy float64 references of the scene passes (importable without Vulkan).

- ``rasterize_depth``: a small triangle rasterizer (pixel centres, max depth wins = the
  GREATER_OR_EQUAL test, optional back-face culling with Vulkan's orientation rule).
- ``depth_prepass_reference``: reversed-Z depth of a scene at one frame.
- ``shadow_map_reference``: one shadow layer's reversed orthographic depth (no bias).
- ``light_setup_reference``: the ``lights`` buffer entries.
- ``shadow_pcf_reference``: the lit fraction computed by ``shaders/scene/shadow.glsl``.

Reference tolerances used by the tests: depth 1e-5 relative (float32 transforms of
float64 matrices) on pixels whose 3x3 neighbourhood shows one draw; light positions 1e-6
relative to their distance from the camera (plus 1e-6 m); directions and radiance 1e-6.
"""

from __future__ import annotations

import numpy as np

from rgraph.scene.build import LIGHT_TYPES, SceneData


def rasterize_depth(clip: np.ndarray, ids: np.ndarray, width: int, height: int, *,
                    cull_back: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``clip`` (n, 3, 4) clip-space triangles -> (depth (h, w), draw id (h, w), -1 where empty).

    Depth = interpolated NDC z (affine in screen space), kept when >= the stored value (clear 0).
    Triangles with a vertex at w <= 0 or outside 0 <= z <= w are skipped (the tests keep
    geometry inside the frustum). Vulkan front faces: counter-clockwise, i.e. positive
    a = -1/2 sum(x_i y_(i+1) - x_(i+1) y_i) in framebuffer coordinates."""
    depth = np.zeros((height, width))
    owner = np.full((height, width), -1, dtype=np.int64)
    w = clip[..., 3]
    valid = np.all(w > 0, axis=1)
    ndc = clip[..., :3] / np.where(w > 0, w, 1.0)[..., None]
    valid &= np.all((ndc[..., 2] >= 0) & (ndc[..., 2] <= 1), axis=1)
    sx = (ndc[..., 0] * 0.5 + 0.5) * width
    sy = (ndc[..., 1] * 0.5 + 0.5) * height
    for t in np.nonzero(valid)[0]:
        x0, x1, x2 = sx[t]
        y0, y1, y2 = sy[t]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if area == 0:
            continue
        vk_area = -0.5 * ((x0 * y1 - x1 * y0) + (x1 * y2 - x2 * y1) + (x2 * y0 - x0 * y2))
        if cull_back and vk_area <= 0:
            continue
        xa, xb = max(int(np.floor(min(x0, x1, x2))), 0), min(int(np.ceil(max(x0, x1, x2))), width - 1)
        ya, yb = max(int(np.floor(min(y0, y1, y2))), 0), min(int(np.ceil(max(y0, y1, y2))), height - 1)
        if xa > xb or ya > yb:
            continue
        px, py = np.meshgrid(np.arange(xa, xb + 1) + 0.5, np.arange(ya, yb + 1) + 0.5)
        b0 = ((x1 - px) * (y2 - py) - (x2 - px) * (y1 - py)) / area
        b1 = ((x2 - px) * (y0 - py) - (x0 - px) * (y2 - py)) / area
        b2 = 1.0 - b0 - b1
        inside = (b0 >= 0) & (b1 >= 0) & (b2 >= 0)
        z = b0 * ndc[t, 0, 2] + b1 * ndc[t, 1, 2] + b2 * ndc[t, 2, 2]
        region = depth[ya:yb + 1, xa:xb + 1]
        take = inside & (z >= region)
        region[take] = z[take]
        owner[ya:yb + 1, xa:xb + 1][take] = ids[t]
    return depth, owner


def scene_triangles(scene: SceneData, frame: int, camera_position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Camera-relative world triangles (n, 3, 4) homogeneous, float64, and each one's draw index."""
    tris, ids = [], []
    models = scene.draw_models(camera_position)
    for mesh in scene.meshes:
        data = scene.deformed(mesh, frame) if mesh.deformer is not None else mesh.data
        pos = np.concatenate([data.positions, np.ones((data.vertex_count, 1))], axis=1)
        for k in range(mesh.instances):
            draw = mesh.first_draw + k
            world = pos @ models[draw][0].T
            tris.append(world[data.indices.astype(np.int64)])
            ids.append(np.full(data.triangle_count, draw))
    return np.concatenate(tris), np.concatenate(ids)


def depth_prepass_reference(scene: SceneData, frame: int, *, cull_back: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Reversed-Z depth (h, w) and owning draw id of ``scene`` at ``frame`` (its extent)."""
    cam = scene.camera(frame)
    world, ids = scene_triangles(scene, frame, cam.position)
    clip = world @ cam.view_proj.T
    w, h = scene.extent
    return rasterize_depth(clip, ids, w, h, cull_back=cull_back)


def shadow_map_reference(scene: SceneData, frame: int, layer: int, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Shadow layer ``layer`` (size x size) without depth bias: reversed depth, 0 = empty."""
    cam = scene.camera(frame)
    world, ids = scene_triangles(scene, frame, cam.position)
    clip = world @ scene.shadow_matrices(cam.position)[layer].T
    return rasterize_depth(clip, ids, size, size, cull_back=False)


def light_setup_reference(scene: SceneData, frame: int) -> np.ndarray:
    """(lights, 16) float64: the ``Light`` structs of scene.glsl for ``frame``."""
    cam = scene.camera(frame)
    rot = cam.view[:3, :3]
    out = np.zeros((len(scene.lights), 16))
    for k, li in enumerate(scene.lights):
        if li.type == LIGHT_TYPES["directional"]:
            to_light = -li.direction
            out[k, 0:4] = (0, 0, 0, li.radius)
            out[k, 4:8] = (*to_light, li.type)
            out[k, 12:16] = (*(rot @ to_light), 0.0)
        else:
            rel = li.position - cam.position
            out[k, 0:4] = (*rel, li.radius)
            axis = -li.direction if li.type == LIGHT_TYPES["spot"] else np.zeros(3)
            out[k, 4:8] = (*axis, li.type)
            out[k, 12:16] = (*(rot @ rel), 1.0 / max(li.radius, 1e-6) ** 2)
        out[k, 8:12] = (*li.radiance, li.shadow_layer)
    return out


def shadow_pcf_reference(shadow_map: np.ndarray, shadow_view_proj: np.ndarray, world_cam_rel: np.ndarray,
                         taps: int, epsilon: float = 1e-5) -> np.ndarray:
    """Lit fraction per point (shadow.glsl's shadow_pcf, nearest texels, clamp to edge)."""
    size_y, size_x = shadow_map.shape
    pts = np.concatenate([world_cam_rel, np.ones((len(world_cam_rel), 1))], axis=1) @ shadow_view_proj.T
    ndc = pts[:, :3] / pts[:, 3:4]
    uv, z = ndc[:, :2] * 0.5 + 0.5, ndc[:, 2]
    inside = np.all((uv >= 0) & (uv <= 1), axis=1) & (z >= 0) & (z <= 1)
    n = max(1, int(round(np.sqrt(max(taps, 1)))))
    lit = np.zeros(len(pts))
    for j in range(n):
        for i in range(n):
            off = (np.array([i, j]) - 0.5 * (n - 1)) / np.array([size_x, size_y])
            t = uv + off
            tx = np.clip(np.floor(t[:, 0] * size_x), 0, size_x - 1).astype(int)
            ty = np.clip(np.floor(t[:, 1] * size_y), 0, size_y - 1).astype(int)
            lit += (z + epsilon >= shadow_map[ty, tx])
    return np.where(inside, lit / (n * n), 1.0)
