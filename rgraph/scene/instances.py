"""Per-instance data of GPU-driven drawing (``draw.mode=gpu``) and the float64 frustum test.

``instance_bytes`` packs the ``Instance`` struct of ``shaders/scene/scene.glsl`` (192 bytes,
std430) once per scene: float64 world translation, float32 high/low split of it, the
object -> world 3x3 and its inverse-transpose, ids and the bounding sphere. ``visible`` is
the reference of ``shaders/scene/cull.comp`` (and the per-object CPU culling of
``draw.mode=naive``): a sphere is kept when it is inside or crosses every plane of some view.
``views_bytes`` packs the ``Views`` uniform of multiview stereo (``views=2``).
"""

from __future__ import annotations

import numpy as np

from rgraph.scene.build import SceneData
from rgraph.scene.camera import model_matrix, normal_matrix
from rgraph.scene.packing import draw_infos, mat, split_hi_lo

INSTANCE_BYTES = 192
MESH_ROW_BYTES = 16
#: Interpupillary distance (metres) of ``views=2`` when ``views.ipd`` is not given.
DEFAULT_IPD = 0.064


def instance_arrays(scene: SceneData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(translations (N, 3) float64 world, sphere centres relative to them (N, 3), radii (N,))
    of every draw in draw order (cached on the scene)."""
    cached = getattr(scene, "_instance_arrays", None)
    if cached is None:
        t, c, r = [], [], []
        for mesh in scene.meshes:
            centre, radius = mesh.bounding_sphere()
            t.append(mesh.positions)
            c.append(np.broadcast_to(centre, mesh.positions.shape))
            r.append(np.full(mesh.instances, radius))
        cached = (np.concatenate(t) if t else np.zeros((0, 3)), np.concatenate(c) if c else np.zeros((0, 3)),
                  np.concatenate(r) if r else np.zeros(0))
        scene._instance_arrays = cached  # type: ignore[attr-defined]
    return cached


def instance_bytes(scene: SceneData) -> bytes:
    """The persistent ``Instances`` buffer (scene.glsl, 192 bytes per draw)."""
    n = scene.draw_count
    rows = np.zeros((max(n, 1), INSTANCE_BYTES // 4), dtype=np.float32)
    ints = rows.view(np.uint32)
    t, centre, radius = instance_arrays(scene)
    k = 0
    for mesh in scene.meshes:
        m = model_matrix(np.zeros(3), mesh.rotation, mesh.scale)
        nm = normal_matrix(m)
        block = slice(k, k + mesh.instances)
        rows[block, 8:20] = np.concatenate([np.append(m[:3, j], 0.0) for j in range(3)]).astype(np.float32)
        rows[block, 20:32] = np.concatenate([np.append(nm[:3, j], 0.0) for j in range(3)]).astype(np.float32)
        k += mesh.instances
    if n:
        ints[:n, 32:36] = draw_infos(scene)
        doubles = np.zeros((n, 4), dtype=np.float64)
        doubles[:, :3] = t
        rows[:n, 0:8] = doubles.view(np.float32).reshape(n, 8)
        hi, lo = split_hi_lo(t)
        rows[:n, 36:39], rows[:n, 40:43] = hi, lo
        rows[:n, 44:47], rows[:n, 47] = centre, radius
    return rows.tobytes()


def frustum_planes(view_proj: np.ndarray) -> np.ndarray:
    """(5, 4) inward planes (a, b, c, d: a x + b y + c z + d >= 0 inside) of a reversed-Z,
    infinite-far Vulkan projection: left, right, bottom, top, near (clip w + x, w - x, w + y,
    w - y, w - z; the far plane is at infinity)."""
    m = np.asarray(view_proj, dtype=np.float64)
    w = m[3]
    return np.stack([w + m[0], w - m[0], w + m[1], w - m[1], w - m[2]])


def visible(scene: SceneData, camera_position: np.ndarray, view_projs: list[np.ndarray]) -> np.ndarray:
    """Bool mask (draws,): the instance's bounding sphere meets the frustum of some view
    (camera-relative, float64). Deformable meshes' instances count as visible."""
    t, centre, radius = instance_arrays(scene)
    c = t - np.asarray(camera_position, dtype=np.float64) + centre
    keep = np.zeros(len(c), dtype=bool)
    for vp in view_projs:
        planes = frustum_planes(vp)
        norms = np.linalg.norm(planes[:, :3], axis=1)
        dist = c @ planes[:, :3].T + planes[:, 3]
        keep |= np.all(dist >= -radius[:, None] * norms[None, :], axis=1)
    return keep


#: Distance buckets of draw.order=front_to_back (shaders/scene/cull.comp BUCKETS).
DRAW_BUCKETS = 256


def draw_buckets(scene: SceneData, frame: int = 0) -> np.ndarray:
    """(draws,) distance bucket of every instance under draw.order=front_to_back, as
    ``cull.comp`` computes it in float32: the nearest point of its bounding sphere, log-spaced
    over [near, far side of the scene bounds] (the Frame's ``scene_bounds``)."""
    cam = scene.camera(frame)
    centre, radius = scene.bounding_sphere_rel(cam.position)
    far_side = float(np.linalg.norm(centre) + radius)
    near = max(float(cam.near), 1e-6)
    far_side = max(far_side, 2.0 * near)
    t, c, radius = instance_arrays(scene)
    d = np.maximum(np.linalg.norm(t - cam.position + c, axis=1) - radius, near)
    u = np.log(d / near) / np.log(far_side / near)
    return np.minimum((np.maximum(u, 0.0) * DRAW_BUCKETS).astype(np.int64), DRAW_BUCKETS - 1)


def mesh_rows(calls: list) -> bytes:
    """The ``Meshes`` table: per scene mesh (index count, first index, vertex offset, 0)."""
    rows = np.zeros((max(len(calls), 1), 4), dtype=np.uint32)
    for k, call in enumerate(calls):
        rows[k] = (call.index_count, call.first_index, call.vertex_offset, 0)
    return rows.tobytes()


def eye_offsets(scene: SceneData, frame: int, views: int, ipd: float) -> np.ndarray:
    """(views, 3) camera-relative eye positions: along the camera's right axis, centred,
    ``ipd`` apart (the left eye first)."""
    right = np.asarray(scene.camera(frame).view, dtype=np.float64)[0, :3]
    return np.array([(k - (views - 1) / 2.0) * ipd * right for k in range(views)])


def eye_view_projs(scene: SceneData, frame: int, views: int, ipd: float) -> list[np.ndarray]:
    """Per eye: camera-relative world -> clip (the camera's rotation and projection, moved to the eye)."""
    cam = scene.camera(frame)
    out = []
    for eye in eye_offsets(scene, frame, views, ipd):
        shift = np.eye(4)
        shift[:3, 3] = -eye
        out.append(np.asarray(cam.view_proj, dtype=np.float64) @ shift)
    return out


def views_bytes(scene: SceneData, frame: int, views: int, ipd: float) -> bytes:
    """The ``Views`` uniform (scene.glsl): view_proj[views] then eye[views] (vec4)."""
    out = np.zeros(views * 20, dtype=np.float32)
    for k, vp in enumerate(eye_view_projs(scene, frame, views, ipd)):
        out[16 * k:16 * k + 16] = mat(vp)
    for k, eye in enumerate(eye_offsets(scene, frame, views, ipd)):
        out[16 * views + 4 * k:16 * views + 4 * k + 3] = eye
    return out.tobytes()


def views_size(views: int) -> int:
    """Bytes of the ``Views`` uniform (a 16-byte stub without multiview)."""
    return views * 80 if views > 1 else 16


def cached_views_bytes(scene: SceneData, frame: int, views: int, ipd: float) -> bytes:
    """``views_bytes``, recomputed only when the camera changes."""
    cam = scene.camera(frame)
    key = (np.asarray(cam.position, dtype=np.float64).tobytes(), np.asarray(cam.view_proj).tobytes(), views, ipd)
    cached = getattr(scene, "_views_cache", None)
    if cached is None or cached[0] != key:
        cached = (key, views_bytes(scene, frame, views, ipd))
        scene._views_cache = cached  # type: ignore[attr-defined]
    return cached[1]


def naive_commands(scene: SceneData, frame: int, calls: list, views: int, ipd: float) -> bytes:
    """draw.mode=naive, every frame: the CPU frustum test of every object and its
    VkDrawIndexedIndirectCommand (instanceCount 1 when visible, 0 when culled), in draw order."""
    table = getattr(scene, "_naive_table", None)
    if table is None:
        table = np.zeros((max(scene.draw_count, 1), 5), dtype=np.uint32)
        for call in calls:
            rows = slice(call.first_instance, call.first_instance + call.instances)
            table[rows, 0], table[rows, 2], table[rows, 3] = call.index_count, call.first_index, call.vertex_offset
            table[rows, 4] = np.arange(call.first_instance, call.first_instance + call.instances)
        scene._naive_table = table  # type: ignore[attr-defined]
    table[:scene.draw_count, 1] = _visible_of_frame(scene, frame, views, ipd)
    return table.tobytes()


def _visible_of_frame(scene: SceneData, frame: int, views: int, ipd: float) -> np.ndarray:
    cam = scene.camera(frame)
    projs = eye_view_projs(scene, frame, views, ipd) if views > 1 else [cam.view_proj]
    return visible(scene, cam.position, projs)


def naive_visible(scene: SceneData, frame: int, views: int, ipd: float) -> list[int]:
    """draw.mode=naive with direct draws, every frame: the CPU frustum test of every object;
    the ids of the visible ones, ascending (a list: the recording loop iterates it)."""
    return np.flatnonzero(_visible_of_frame(scene, frame, views, ipd)).tolist()
