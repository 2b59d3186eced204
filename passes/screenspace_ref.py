"""Camera math shared by the screen-space passes (HBAO, decals, SSS) and their references.

Pure NumPy (float64), no Vulkan. Conventions (the same as ``shaders/scene/scene.glsl``'s
``Frame`` is documented to use):

- camera-relative world: the camera sits at the origin, world axes unchanged;
- view space: right-handed, looking down -z, +y up;
- projection: reversed-Z with an infinite far plane, Vulkan clip space (y down):
  ``clip = (P00 x, P11 y, near, -z)`` with ``P11 = -P00 * aspect`` (negative: y flip),
  so ``depth = near / -z`` (1 at the near plane, 0 at infinity: "sky" is depth 0);
- pixel ``(i, j)`` has its centre at ``uv = ((i + .5) / w, (j + .5) / h)``, ``ndc = 2 uv - 1``.

``screen_camera`` is the accessor the passes use to get these values: the plan's scene file
camera when the plan has one, else the graph params ``camera.fov_y`` / ``camera.near`` /
``camera.position`` / ``camera.look_at``; the params override the scene when given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

DEFAULT_FOV_Y = 45.0
DEFAULT_NEAR = 0.01


@dataclass(frozen=True)
class Camera:
    """A pinhole camera: vertical field of view (degrees), near plane, aspect w/h, pose."""

    fov_y: float = DEFAULT_FOV_Y
    near: float = DEFAULT_NEAR
    aspect: float = 1.0
    position: tuple[float, float, float] = (0.0, 0.0, 1.0)
    look_at: tuple[float, float, float] = (0.0, 0.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)

    @property
    def focal(self) -> float:
        """1 / tan(fov_y / 2)."""
        return 1.0 / math.tan(math.radians(self.fov_y) / 2.0)

    @property
    def p00(self) -> float:
        return self.focal / self.aspect

    @property
    def p11(self) -> float:
        return -self.focal

    def proj(self) -> np.ndarray:
        """Reversed-Z, infinite-far projection (column vectors: clip = proj @ view_pos)."""
        return np.array([[self.p00, 0, 0, 0], [0, self.p11, 0, 0], [0, 0, 0, self.near], [0, 0, -1, 0]],
                        dtype=np.float64)

    def view(self) -> np.ndarray:
        """Camera-relative world -> view: a rotation only (the camera is the origin)."""
        eye = np.asarray(self.position, np.float64)
        forward = np.asarray(self.look_at, np.float64) - eye
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, np.asarray(self.up, np.float64))
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = right, up, -forward
        return m

    def view_proj(self) -> np.ndarray:
        return self.proj() @ self.view()

    def inv_view_proj(self) -> np.ndarray:
        return np.linalg.inv(self.view_proj())


def linear_depth(depth: np.ndarray, near: float) -> np.ndarray:
    """View distance along -z from reversed-Z infinite depth (inf for sky, depth 0)."""
    d = np.asarray(depth, np.float64)
    with np.errstate(divide="ignore"):
        return np.where(d > 0, near / np.where(d > 0, d, 1.0), np.inf)


def view_position(depth: np.ndarray | float, uv: np.ndarray, cam: Camera) -> np.ndarray:
    """View-space positions (..., 3) of depths at texture coordinates ``uv`` (..., 2)."""
    z = linear_depth(np.asarray(depth), cam.near)
    ndc = 2.0 * np.asarray(uv, np.float64) - 1.0
    return np.stack([ndc[..., 0] * z / cam.p00, ndc[..., 1] * z / cam.p11, -z], axis=-1)


def pixel_uv(width: int, height: int) -> np.ndarray:
    """(h, w, 2) texture coordinates of the pixel centres."""
    x = (np.arange(width) + 0.5) / width
    y = (np.arange(height) + 0.5) / height
    return np.stack(np.meshgrid(x, y), axis=-1)


def depth_of_view_z(z_view: np.ndarray, near: float) -> np.ndarray:
    """Reversed-Z depth of view-space z (negative in front of the camera)."""
    return near / -np.asarray(z_view, np.float64)


def render_depth(width: int, height: int, cam: Camera, *, planes: list[tuple[Any, Any]] = (),
                 spheres: list[tuple[Any, float]] = (), boxes: list[tuple[Any, Any]] = ()) -> np.ndarray:
    """Ray-cast a small analytic view-space scene into a reversed-Z depth image (h, w) float64.

    ``planes``: (point, normal); ``spheres``: (centre, radius); ``boxes``: (min, max) corners,
    all in view space. Pixels that hit nothing are sky (depth 0). Test-input generator.
    """
    uv = pixel_uv(width, height)
    ndc = 2.0 * uv - 1.0
    rays = np.stack([ndc[..., 0] / cam.p00, ndc[..., 1] / cam.p11, -np.ones(ndc.shape[:2])], axis=-1)
    t_best = np.full((height, width), np.inf)
    for point, normal in planes:
        n = np.asarray(normal, np.float64)
        denom = rays @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(np.abs(denom) > 1e-12, np.dot(np.asarray(point, np.float64), n) / denom, np.inf)
        t_best = np.where((t > 0) & (t < t_best), t, t_best)
    for centre, radius in spheres:
        c = np.asarray(centre, np.float64)
        a = np.sum(rays * rays, axis=-1)
        b = rays @ c
        disc = b * b - a * (c @ c - radius * radius)
        with np.errstate(invalid="ignore"):
            t = np.where(disc >= 0, (b - np.sqrt(np.maximum(disc, 0))) / a, np.inf)
        t_best = np.where((t > 0) & (t < t_best), t, t_best)
    for lo, hi in boxes:
        lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = lo / rays, hi / rays
        tmin = np.nanmax(np.minimum(t1, t2), axis=-1)
        tmax = np.nanmin(np.maximum(t1, t2), axis=-1)
        hit = (tmax >= tmin) & (tmin > 0)
        t_best = np.where(hit & (tmin < t_best), tmin, t_best)
    z = t_best  # rays have z = -1, so t is the view distance
    with np.errstate(divide="ignore"):
        return np.where(np.isfinite(z), cam.near / z, 0.0)


def camera_from_params(params: dict, aspect: float, base: Camera | None = None) -> Camera:
    """``base`` (or the defaults) with ``camera.*`` params applied."""
    b = base or Camera(aspect=aspect)

    def vec(name: str, default: tuple) -> tuple:
        value = params.get(name)
        if value is None:
            return default
        if isinstance(value, str):
            value = [float(x) for x in value.replace("[", "").replace("]", "").split(",")]
        return tuple(float(x) for x in value)

    return Camera(fov_y=float(params.get("camera.fov_y", b.fov_y)), near=float(params.get("camera.near", b.near)),
                  aspect=aspect, position=vec("camera.position", b.position), look_at=vec("camera.look_at", b.look_at),
                  up=vec("camera.up", b.up))


def scene_camera(scene_path: str, aspect: float) -> Camera:
    """The camera of a scene file (FORMAT.md 2)."""
    from rgraph.spec.scene import load_scene

    c = load_scene(scene_path).model.camera
    return Camera(fov_y=float(c.fov_y), near=float(c.near), aspect=aspect, position=tuple(map(float, c.position)),
                  look_at=tuple(map(float, c.look_at)), up=tuple(map(float, c.up)))


def screen_camera(plan: dict, params: dict, extent: tuple[int, int]) -> Camera:
    """The camera a screen-space pass uses: the plan's scene camera, then ``camera.*`` params."""
    aspect = extent[0] / extent[1]
    base = scene_camera(plan["scene_source"], aspect) if plan.get("scene_source") else None
    return camera_from_params(params, aspect, base)
