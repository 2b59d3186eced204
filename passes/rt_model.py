"""The ray tracing lighting model shared by ``rt_standalone`` (GPU) and its NumPy reference.

Everything is camera-relative (world position - camera, formed in float64), so ray origins
stay near 0 in large worlds. Per scene (``rt_tables``): a table per instance (its camera-
relative object->world 3x4, normal matrix, material), the meshes' object-space positions,
normals and indices, the materials and the lights, packed as the std430 structs of
``shaders/rt/common.glsl``.

Materials: ``kr`` = reflective, ``kt`` = refractive (scaled so kr + kt <= 1), the rest is
opaque Phong: ambient + per light (shadow ray) albedo * N.L + ks * (R.V)^n with
ks = 0.25 (1 - roughness), n = 2 + 126 (1 - roughness)^2. Reflections weigh kr, refractions
kt * albedo (total internal reflection turns the refraction into a reflection). Rays that
miss sample the background cube map (``sky``). ``rt.max_depth`` bounds the ray tree depth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgraph.scene.build import SceneData
from rgraph.scene.camera import inverse_transpose3, model_matrix

SKY_ZENITH = np.array([0.20, 0.40, 0.90])
SKY_HORIZON = np.array([0.75, 0.80, 0.95])
SKY_GROUND = np.array([0.22, 0.20, 0.18])
MAX_LIGHTS = 16
MAX_STACK = 17  # rt.max_depth <= 16


def sky(d: np.ndarray) -> np.ndarray:
    """Background radiance in direction ``d`` (unit; any leading shape)."""
    d = np.asarray(d, dtype=np.float64)
    y = d[..., 1:2]
    up = SKY_HORIZON + (SKY_ZENITH - SKY_HORIZON) * np.clip(y, 0.0, 1.0)
    down = SKY_GROUND + (SKY_HORIZON - SKY_GROUND) * np.clip(1.0 + 4.0 * y, 0.0, 1.0)
    return np.where(y >= 0.0, up, down)


def cube_face_uv(d: np.ndarray) -> tuple[int, float, float]:
    """Vulkan cube map face (0..5: +x -x +y -y +z -z) and (u, v) in [0, 1] of direction ``d``."""
    x, y, z = (float(c) for c in d)
    ax, ay, az = abs(x), abs(y), abs(z)
    if ax >= ay and ax >= az:
        face, sc, tc, ma = (0, -z, -y, ax) if x >= 0 else (1, z, -y, ax)
    elif ay >= az:
        face, sc, tc, ma = (2, x, z, ay) if y >= 0 else (3, x, -z, ay)
    else:
        face, sc, tc, ma = (4, x, -y, az) if z >= 0 else (5, -x, -y, az)
    ma = max(ma, 1e-30)
    return face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0)


def cube_texel_dir(face: int, i: int, j: int, size: int) -> np.ndarray:
    """The unit direction through the centre of texel (i, j) of ``face``."""
    sc = 2.0 * (i + 0.5) / size - 1.0
    tc = 2.0 * (j + 0.5) / size - 1.0
    d = [(1.0, -tc, -sc), (-1.0, -tc, sc), (sc, 1.0, tc), (sc, -1.0, -tc), (sc, -tc, 1.0), (-sc, -tc, -1.0)][face]
    v = np.array(d)
    return v / np.linalg.norm(v)


def sky_cubemap(size: int) -> np.ndarray:
    """(6, size, size, 3) float16-rounded radiance at each texel centre (what the GPU stores)."""
    out = np.zeros((6, size, size, 3))
    for f in range(6):
        for j in range(size):
            for i in range(size):
                out[f, j, i] = sky(cube_texel_dir(f, i, j, size))
    return out.astype(np.float16).astype(np.float64)


def sample_sky(cube: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Nearest texel of the cube map in direction ``d``."""
    size = cube.shape[1]
    face, u, v = cube_face_uv(d)
    i = min(int(u * size), size - 1)
    j = min(int(v * size), size - 1)
    return cube[face, j, i]


@dataclass(frozen=True)
class Material:
    albedo: np.ndarray
    kr: float
    kt: float
    ior: float
    ks: float
    shininess: float


def material_of(m) -> Material:
    kr, kt = float(m.reflective), float(m.refractive)
    total = kr + kt
    if total > 1.0:
        kr, kt = kr / total, kt / total
    rough = float(m.roughness)
    return Material(np.asarray(m.base_color, dtype=np.float64), kr, kt, float(m.ior), 0.25 * (1.0 - rough),
                    2.0 + 126.0 * (1.0 - rough) ** 2)


@dataclass
class Tables:
    """Camera-relative scene data for tracing (float64; the GPU gets float32 copies)."""

    camera: np.ndarray  # world position
    basis: np.ndarray  # (3, 3) rows: right, up, forward (unit)
    tan_half_fov: float
    triangles: np.ndarray  # (T, 3, 3) camera-relative world vertices
    tri_normals: np.ndarray  # (T, 3, 3) world vertex normals
    tri_material: np.ndarray  # (T,) material index
    materials: list[Material]
    lights: list[tuple[int, np.ndarray, np.ndarray]]  # (type 0 dir | 1 point, dir-or-camera-relative pos, radiance)


def camera_basis(data: SceneData) -> tuple[np.ndarray, np.ndarray, float]:
    """Camera world position, (right, up, forward) rows as the raster camera's view matrix."""
    from rgraph.scene.camera import orthonormal_basis

    c = data.model.camera
    pos = np.asarray(c.position, dtype=np.float64)
    right, up, fwd = orthonormal_basis(np.asarray(c.look_at, dtype=np.float64) - pos, c.up)
    return pos, np.stack([right, up, fwd]), float(np.tan(np.radians(c.fov_y) / 2.0))


def object_geometry(mesh, seconds: float | None) -> tuple[np.ndarray, np.ndarray]:
    """A mesh's object-space (positions, normals) as ray tracing sees them: the rest mesh, or
    for a deformable mesh at scene time ``seconds`` (not None) the deformed one
    (``Deformer.traced``). Skinned meshes stay in their rest pose."""
    if seconds is not None and mesh.deformer is not None:
        pos, nrm = mesh.deformer.traced(seconds)
        return pos.astype(np.float64), nrm
    return mesh.data.positions, mesh.data.normals


def build_tables(data: SceneData, seconds: float | None = None) -> Tables:
    """``seconds``: the scene time of the deformable meshes (None: every mesh at rest)."""
    cam, basis, tan_half = camera_basis(data)
    tris, norms, mats = [], [], []
    for mesh in data.meshes:
        positions, normals = object_geometry(mesh, seconds)
        for p in mesh.positions:
            m = model_matrix(p - cam, mesh.rotation, mesh.scale)
            nm = inverse_transpose3(m)
            pos = positions @ m[:3, :3].T + m[:3, 3]
            nrm = normals @ nm.T
            tris.append(pos[mesh.data.indices])
            norms.append(nrm[mesh.data.indices])
            mats.append(np.full(len(mesh.data.indices), mesh.material))
    lights = []
    for li in data.lights[:MAX_LIGHTS]:
        if li.type == 0:
            lights.append((0, -li.direction, li.radiance))
        else:
            lights.append((1, li.position - cam, li.radiance))
    return Tables(cam, basis, tan_half, np.concatenate(tris), np.concatenate(norms), np.concatenate(mats),
                  [material_of(m) for m in data.materials], lights)


def primary_dir(t: Tables, x: int, y: int, w: int, h: int) -> np.ndarray:
    sx = (2.0 * (x + 0.5) / w - 1.0) * t.tan_half_fov * (w / h)
    sy = (1.0 - 2.0 * (y + 0.5) / h) * t.tan_half_fov
    d = t.basis[2] + sx * t.basis[0] + sy * t.basis[1]
    return d / np.linalg.norm(d)
