"""Camera and transform matrices in float64, camera-relative (the camera sits at the origin).

- ``view_rotation``: camera-relative world -> view, rotation only (right, up, -forward rows).
- ``perspective``: reversed-Z, infinite far plane, Vulkan clip (Y flipped):
  NDC depth = near / -z_view (1 at the near plane, 0 at infinity).
- ``model_matrix``: object -> world: translate @ R @ scale with R = Rz @ Ry @ Rx (degrees,
  X applied first). Relative models use ``position - camera`` as the translation, formed in
  float64 before any cast to float32.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WORLD_UP = np.array([0.0, 1.0, 0.0])


def _unit(v: np.ndarray) -> np.ndarray:
    """``v / |v|``, scaled by its largest component first: a vector the scene validator accepts
    (finite, nonzero ``math.hypot``) normalizes even where its squared norm over- or underflows
    (a camera 1e300 m out, a look_at 1e-200 m away)."""
    v = np.asarray(v, dtype=np.float64)
    m = float(np.max(np.abs(v))) if v.size else 0.0
    if not np.isfinite(m) or m == 0.0:
        raise ValueError(f"cannot normalize {v}")
    w = v / m
    return w / float(np.linalg.norm(w))


def unit_or(v: np.ndarray, fallback) -> np.ndarray:
    """:func:`_unit` of ``v``, or ``fallback`` (a unit vector) where ``v`` is zero or not finite."""
    try:
        return _unit(v)
    except ValueError:
        return np.asarray(fallback, dtype=np.float64)


def orthonormal_basis(forward, up=WORLD_UP) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(right, up, forward) unit and orthogonal. When ``forward`` is (anti)parallel to ``up``
    another reference axis is used, so the basis never degenerates into NaN."""
    f = _unit(np.asarray(forward, dtype=np.float64))
    ref = _unit(np.asarray(up, dtype=np.float64))
    if abs(float(f @ ref)) > 0.999:
        candidates = np.eye(3)
        ref = candidates[int(np.argmin(np.abs(candidates @ f)))]
    r = _unit(np.cross(f, ref))
    u = np.cross(r, f)
    return r, u, f


def view_rotation(forward, up=WORLD_UP) -> np.ndarray:
    """4x4 view matrix without translation (camera-relative world -> view)."""
    r, u, f = orthonormal_basis(forward, up)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = r, u, -f
    return m


def perspective(fov_y_deg: float, aspect: float, near: float) -> np.ndarray:
    """Reversed-Z infinite perspective with Vulkan's downward clip Y."""
    f = 1.0 / np.tan(np.radians(fov_y_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = -f
    m[2, 3] = near
    m[3, 2] = -1.0
    return m


def euler_rotation(degrees) -> np.ndarray:
    """3x3 rotation Rz @ Ry @ Rx of ``degrees`` (x, y, z)."""
    ax, ay, az = np.radians(np.asarray(degrees, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def model_matrix(translation, rotation_deg=(0, 0, 0), scale=1.0) -> np.ndarray:
    """4x4 object -> world (or camera-relative world when ``translation`` is relative)."""
    s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,))
    m = np.eye(4)
    m[:3, :3] = euler_rotation(rotation_deg) * s[None, :]
    m[:3, 3] = np.asarray(translation, dtype=np.float64)
    return m


def inverse_transpose3(a: np.ndarray) -> np.ndarray:
    """The inverse-transpose of the 3x3 ``a`` (normals; rescale after use). A singular ``a``
    (a zero scale: a flattened or vanished mesh) gives its cofactor matrix, ``det(a) *
    inverse-transpose`` where that exists: the same directions, and normals of the faces that
    keep an area (a mesh flattened to a plane keeps the plane's normal)."""
    a = np.asarray(a, dtype=np.float64)[:3, :3]
    try:
        return np.linalg.inv(a).T
    except np.linalg.LinAlgError:
        c0, c1, c2 = a[:, 0], a[:, 1], a[:, 2]
        return np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=1)


def normal_matrix(model: np.ndarray) -> np.ndarray:
    """4x4 holding the inverse-transpose of ``model``'s 3x3 (normals; rescale after use;
    :func:`inverse_transpose3`)."""
    m = np.eye(4)
    m[:3, :3] = inverse_transpose3(model)
    return m


def ortho_reversed(lo, hi) -> np.ndarray:
    """Orthographic light-space box [lo, hi] (x, y, distance along the light) -> clip with
    reversed depth: 1 at distance lo[2] (nearest the light), 0 at hi[2]. No Y flip."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    span = np.maximum(hi - lo, 1e-9)
    m = np.eye(4)
    m[0, 0], m[0, 3] = 2.0 / span[0], -(hi[0] + lo[0]) / span[0]
    m[1, 1], m[1, 3] = 2.0 / span[1], -(hi[1] + lo[1]) / span[1]
    m[2, 2], m[2, 3] = -1.0 / span[2], hi[2] / span[2]
    return m


def shadow_view_proj(direction, points_rel: np.ndarray, margin: float = 0.02) -> np.ndarray:
    """Camera-relative world -> light clip for a directional light travelling along
    ``direction``, fitted to ``points_rel`` (e.g. the corners of the scene's bounding boxes,
    camera-relative) with a relative ``margin``."""
    r, u, f = orthonormal_basis(direction)
    basis = np.stack([r, u, f])  # rows: light x, y, depth axis
    centre = (points_rel.min(axis=0) + points_rel.max(axis=0)) / 2.0
    local = (points_rel - centre) @ basis.T
    lo, hi = local.min(axis=0), local.max(axis=0)
    pad = (hi - lo).max() * margin + 1e-6
    lo, hi = lo - pad, hi + pad
    view = np.eye(4)
    view[:3, :3] = basis
    view[:3, 3] = -basis @ centre
    return ortho_reversed(lo, hi) @ view


@dataclass(frozen=True)
class CameraState:
    """The camera of one frame: world position (float64) and camera-relative matrices (float64)."""

    position: np.ndarray
    view: np.ndarray
    proj: np.ndarray
    near: float
    fov_y_deg: float
    aspect: float

    @property
    def view_proj(self) -> np.ndarray:
        return self.proj @ self.view

    @property
    def inv_view_proj(self) -> np.ndarray:
        return np.linalg.inv(self.view_proj)

    @property
    def inv_proj(self) -> np.ndarray:
        return np.linalg.inv(self.proj)

    @property
    def inv_view(self) -> np.ndarray:
        return self.view.T.copy()  # rotation only


def camera_state(position, look_at, up, fov_y_deg: float, near: float, aspect: float) -> CameraState:
    pos = np.asarray(position, dtype=np.float64)
    view = view_rotation(np.asarray(look_at, dtype=np.float64) - pos, up)
    return CameraState(pos, view, perspective(fov_y_deg, aspect, near), float(near), float(fov_y_deg), float(aspect))
