"""NumPy packing of the GPU structs declared in ``shaders/scene/scene.glsl`` (byte for byte).

Matrices are written column-major (``M.T`` as float32), as GLSL reads them. Sizes and
offsets here are the ones written in scene.glsl's comments; tests check both sides.
"""

from __future__ import annotations

import numpy as np

from rgraph.scene.build import AMBIENT, LIGHT_TYPES, MAX_SHADOW_LIGHTS, SceneData
from rgraph.scene.shapes import MeshData

FRAME_BYTES = 800
DRAW_BYTES = 144
MATERIAL_BYTES = 64
SCENE_LIGHT_BYTES = 64
DECAL_BYTES = 96
LIGHT_BYTES = 64  # the graph's `lights` buffer entries (light_setup output)
VERTEX_BYTES = 24  # vec3 position, vec3 normal
DRAW_SKINNED = 2  # Draw.info.z flag (1: deformable); bits 8..31: the mesh's bone stride (instances)

FRAME_OFFSETS = {
    "view": 0, "proj": 64, "view_proj": 128, "inv_view_proj": 192, "inv_proj": 256, "inv_view": 320,
    "shadow_view_proj": 384, "viewport": 640, "counts": 656, "counts2": 672, "time": 688, "sun_direction": 704,
    "sun_radiance": 720, "ambient": 736, "camera_hi": 752, "camera_lo": 768, "scene_bounds": 784,
}


def mat(m: np.ndarray) -> np.ndarray:
    """A 4x4 float64 matrix as 16 column-major float32 values."""
    return np.asarray(m, dtype=np.float64).T.astype(np.float32).reshape(16)


def split_hi_lo(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """float64 -> (float32 high part, float32 remainder): hi + lo == p to ~2^-48 relative."""
    p = np.asarray(p, dtype=np.float64)
    hi = p.astype(np.float32)
    lo = (p - hi.astype(np.float64)).astype(np.float32)
    return hi, lo


def frame_bytes(scene: SceneData, frame: int, seconds: float | None = None) -> bytes:
    """The Frame uniform for ``frame`` (at scene time ``seconds``: default the frame's). Everything
    but the time fields depends on the camera alone and is cached per camera state (the
    per-frame cost is the camera and a copy)."""
    cam = scene.camera(frame)
    key = (np.asarray(cam.position, dtype=np.float64).tobytes(), np.asarray(cam.view_proj).tobytes())
    cached = getattr(scene, "_frame_cache", None)
    if cached is None or cached[0] != key:
        cached = (key, _frame_for_camera(scene, cam))
        scene._frame_cache = cached  # type: ignore[attr-defined]
    f = cached[1].copy()
    o = FRAME_OFFSETS["time"] // 4
    f[o:o + 4] = (scene.seconds(frame) if seconds is None else seconds, float(frame), cam.near,
                  np.radians(cam.fov_y_deg))
    return f.tobytes()


def _frame_for_camera(scene: SceneData, cam) -> np.ndarray:
    f = np.zeros(FRAME_BYTES // 4, dtype=np.float32)
    i = f.view(np.int32)

    def put(name: str, values) -> None:
        o = FRAME_OFFSETS[name] // 4
        arr = np.asarray(values, dtype=np.float32).reshape(-1)
        f[o:o + len(arr)] = arr

    put("view", mat(cam.view))
    put("proj", mat(cam.proj))
    put("view_proj", mat(cam.view_proj))
    put("inv_view_proj", mat(cam.inv_view_proj))
    put("inv_proj", mat(cam.inv_proj))
    put("inv_view", mat(cam.inv_view))
    shadows = scene.shadow_matrices(cam.position)
    for k in range(MAX_SHADOW_LIGHTS):
        o = FRAME_OFFSETS["shadow_view_proj"] // 4 + 16 * k
        f[o:o + 16] = mat(shadows[k] if k < len(shadows) else np.eye(4))
    w, h = scene.extent
    put("viewport", (w, h, 1.0 / w, 1.0 / h))
    o = FRAME_OFFSETS["counts"] // 4
    directional = sum(1 for li in scene.lights if li.type == LIGHT_TYPES["directional"])
    i[o:o + 8] = (len(scene.lights), len(scene.shadow_lights), len(scene.decals), scene.point_light_count,
                  len(scene.materials), scene.draw_count, directional, len(scene.deformable))
    sun = next((li for li in scene.lights if li.type == LIGHT_TYPES["directional"]), None)
    if sun is not None:
        put("sun_direction", (*(-sun.direction), float(sun.shadow_layer)))
        put("sun_radiance", (*sun.radiance, 0.0))
    else:
        put("sun_direction", (0.0, 1.0, 0.0, -1.0))
    put("ambient", (*AMBIENT, 0.0))
    hi, lo = split_hi_lo(cam.position)
    put("camera_hi", (*hi, 0.0))
    put("camera_lo", (*lo, 0.0))
    centre, radius = scene.bounding_sphere_rel(cam.position)
    put("scene_bounds", (*centre, radius))
    return f


def draw_infos(scene: SceneData) -> np.ndarray:
    """(draws, 4) uint32 ``info`` of every draw (scene.glsl Draw.info and Instance.info alike):
    material, mesh index, flags (1 deformable; 2 skinned, bits 8..31 its mesh's bone stride),
    a skinned draw's first bone entry in a logic state."""
    out = np.zeros((scene.draw_count, 4), dtype=np.uint32)
    for index, mesh in enumerate(scene.meshes):
        d = slice(mesh.first_draw, mesh.first_draw + mesh.instances)
        out[d, 0], out[d, 1] = mesh.material, index
        if mesh.deformer is not None:
            out[d, 2] = 1
        if mesh.animator is not None:
            out[d, 2] = DRAW_SKINNED | (mesh.instances << 8)
            out[d, 3] = mesh.bone_base + np.arange(mesh.instances)
    return out


def _draw_table(scene: SceneData) -> tuple[np.ndarray, np.ndarray]:
    """Per scene, once: (N, 4, 4) float64 world model matrices and the packed (N, DRAW_BYTES/4)
    float32 rows with everything but the camera-relative model (normal matrix, ids)."""
    table = getattr(scene, "_packed_draw_table", None)
    if table is None:
        draws = scene.draw_models(np.zeros(3))  # relative to the origin: world space
        world = np.stack([m for m, *_ in draws]) if draws else np.zeros((0, 4, 4))
        rows = np.zeros((max(len(draws), 1), DRAW_BYTES // 4), dtype=np.float32)
        ints = rows.view(np.uint32)
        for k, (_model, normal, *_ids) in enumerate(draws):
            rows[k, 16:32] = mat(normal)
        ints[:len(draws), 32:36] = draw_infos(scene)
        table = (world, rows)
        scene._packed_draw_table = table  # type: ignore[attr-defined]
    return table


def draws_bytes(scene: SceneData, frame: int) -> bytes:
    """The Draws buffer for ``frame``: camera-relative model matrices (translation minus the
    camera formed in float64, then cast) - vectorized over draws; the rest is cached."""
    world, rows = _draw_table(scene)
    n = len(world)
    if n:
        rel = world.copy()
        rel[:, :3, 3] -= np.asarray(scene.camera(frame).position, dtype=np.float64)
        rows[:n, 0:16] = rel.transpose(0, 2, 1).astype(np.float32).reshape(n, 16)
    return rows.tobytes()


def materials_bytes(scene: SceneData) -> bytes:
    out = np.zeros((max(len(scene.materials), 1), MATERIAL_BYTES // 4), dtype=np.float32)
    for k, m in enumerate(scene.materials):
        out[k] = (*m.base_color, m.opacity, m.roughness, m.metallic, m.sss, m.reflective,
                  m.refractive, m.ior, m.baked_ao, 0.0, *m.emissive, 0.0)
    return out.tobytes()


def scene_lights_bytes(scene: SceneData) -> bytes:
    """SceneLights (scene.glsl): spot lights carry cos(inner) in direction.w and cos(outer) in
    radiance.w (they cast no shadows and shaders use no intensity)."""
    n = len(scene.lights)
    out = np.zeros((max(n, 1), SCENE_LIGHT_BYTES // 4), dtype=np.float32)
    if n:
        pos = np.array([li.position for li in scene.lights], dtype=np.float64)
        hi, lo = split_hi_lo(pos)
        spot = np.array([li.type == LIGHT_TYPES["spot"] for li in scene.lights])
        out[:n, 0:3], out[:n, 4:7] = hi, lo
        out[:n, 3] = [li.type for li in scene.lights]
        out[:n, 7] = [li.radius for li in scene.lights]
        out[:n, 8:11] = [li.direction for li in scene.lights]
        out[:n, 11] = np.where(spot, [li.cos_inner for li in scene.lights], [li.shadow_layer for li in scene.lights])
        out[:n, 12:15] = [li.radiance for li in scene.lights]
        out[:n, 15] = np.where(spot, [li.cos_outer for li in scene.lights], [li.intensity for li in scene.lights])
    return out.tobytes()


def decals_bytes(scene: SceneData, frame: int) -> bytes:
    """The Decals buffer for ``frame`` (camera-relative boxes; cached per camera position)."""
    position = np.asarray(scene.camera(frame).position, dtype=np.float64)
    cached = getattr(scene, "_decals_cache", None)
    if cached is None or cached[0] != position.tobytes():
        cached = (position.tobytes(), _decals_for_camera(scene, frame))
        scene._decals_cache = cached  # type: ignore[attr-defined]
    return cached[1]


def _decals_for_camera(scene: SceneData, frame: int) -> bytes:
    out = np.zeros((max(len(scene.decals), 1), DECAL_BYTES // 4), dtype=np.float32)
    for k, (d, m) in enumerate(zip(scene.decals, scene.decal_matrices(scene.camera(frame).position), strict=True)):
        out[k, 0:16] = mat(m)
        out[k, 16:24] = (*d.material.base_color, d.material.opacity, d.material.roughness, d.material.metallic, 0, 0)
    return out.tobytes()


def vertex_bytes(mesh: MeshData) -> bytes:
    v = np.concatenate([mesh.positions, mesh.normals], axis=1).astype(np.float32)
    return np.ascontiguousarray(v).tobytes()


def unpack_lights(data: bytes, count: int) -> np.ndarray:
    """The `lights` buffer (light_setup output) as (count, 16) float32."""
    return np.frombuffer(bytes(data[:count * LIGHT_BYTES]), dtype=np.float32).reshape(count, 16)
