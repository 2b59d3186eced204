"""NumPy float64 reference of clustered forward lighting (importable without Vulkan).

Mirrors ``shaders/clustered/clusters.glsl`` (froxel grid), ``assign.comp`` (which lights a froxel
lists) and ``lights.glsl`` (the bounded point/spot light terms), with the BRDF of
``forward_ref``.

Tolerances used by the tests:
- froxel bounds: 1e-5 relative to the largest coordinate of the froxel (float32 exp2/log2);
- assignment: the GPU list of a froxel holds every light the float64 test accepts with the
  sphere and the froxel shrunk by ``ASSIGN_MARGIN`` (of the radius; of the froxel's largest
  finite coordinate), and none that it rejects with them grown by as much (the GPU pads the
  froxel by 1e-4 of its slice's far distance and the radius by 1e-4);
- shading: |gpu - ref| <= 0.01 |ref| + 0.002 per channel of the hdr output (float16 storage,
  float32 arithmetic), and clustered == all_lights within one 8-bit code after tonemapping.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import forward_ref as brdf

PAD, PAD_ABS = 1e-4, 1e-6
LIGHT_MIN_RADIUS = 1e-6
INFINITY = 1e30
ASSIGN_MARGIN = 1e-3
LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT = 0, 1, 2


@dataclass(frozen=True)
class Grid:
    extent: tuple[int, int]  # output (w, h)
    tiles: tuple[int, int]
    slices: int
    near: float
    far: float
    proj: np.ndarray  # view -> clip (camera.perspective)

    @property
    def froxels(self) -> int:
        return self.tiles[0] * self.tiles[1] * self.slices

    @property
    def tile_px(self) -> tuple[int, int]:
        return -(-self.extent[0] // self.tiles[0]), -(-self.extent[1] // self.tiles[1])


def auto_far(scene, frame: int = 0) -> float:
    """``cluster_far`` with ``clusters.far = 0``: |centre| + radius of the scene's bounding sphere."""
    centre, radius = scene.bounding_sphere_rel(scene.camera(frame).position)
    return float(np.linalg.norm(centre) + radius)


def grid_for(scene, tile: int, slices: int, far: float = 0.0, frame: int = 0) -> Grid:
    """The grid the graph's images give: floor(output / tile) tiles (at least 1)."""
    w, h = scene.extent
    cam = scene.camera(frame)
    near = cam.near
    f = far if far > 0 else auto_far(scene, frame)
    return Grid((w, h), (max(1, int(w * (1 / tile))), max(1, int(h * (1 / tile)))), slices, near,
                max(f, 2 * near), cam.proj)


def slice_starts(g: Grid) -> np.ndarray:
    """(slices + 1,) view distances; the last is INFINITY."""
    k = np.arange(g.slices + 1, dtype=np.float64)
    d = g.near * (g.far / g.near) ** (k / g.slices)
    d[-1] = INFINITY
    return d


def slice_of(g: Grid, d: np.ndarray) -> np.ndarray:
    t = np.log2(np.maximum(d, g.near) / g.near) / np.log2(g.far / g.near)
    return np.clip(np.floor(t * g.slices).astype(np.int64), 0, g.slices - 1)


def froxel_bounds(g: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Unpadded view-space AABBs: (lo, hi) each (gy, gx, slices, 3)."""
    (gx, gy), (tx, ty), (w, h) = g.tiles, g.tile_px, g.extent
    x0 = np.arange(gx) * tx
    y0 = np.arange(gy) * ty
    x1, y1 = np.minimum(x0 + tx, w), np.minimum(y0 + ty, h)
    nx = np.stack([x0 / w * 2 - 1, x1 / w * 2 - 1], axis=-1)  # (gx, 2)
    ny = np.stack([y0 / h * 2 - 1, y1 / h * 2 - 1], axis=-1)
    d = slice_starts(g)
    dd = np.stack([d[:-1], d[1:]], axis=-1)  # (s, 2)
    inv_x, inv_y = 1.0 / g.proj[0, 0], 1.0 / g.proj[1, 1]
    px = nx[None, :, None, :, None] * inv_x * dd[None, None, :, None, :]  # (1, gx, s, 2, 2)
    py = ny[:, None, None, :, None] * inv_y * dd[None, None, :, None, :]  # (gy, 1, s, 2, 2)
    shape = (gy, gx, g.slices)
    lo = np.stack([np.broadcast_to(px.min(axis=(-1, -2)), shape), np.broadcast_to(py.min(axis=(-1, -2)), shape),
                   np.broadcast_to(-dd[:, 1], shape)], axis=-1)
    hi = np.stack([np.broadcast_to(px.max(axis=(-1, -2)), shape), np.broadcast_to(py.max(axis=(-1, -2)), shape),
                   np.broadcast_to(-dd[:, 0], shape)], axis=-1)
    return lo, hi


def padded(g: Grid, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """build.comp's padding: PAD x the slice's far distance (near for the last slice) + PAD_ABS."""
    d = slice_starts(g)
    scale = np.where(np.arange(g.slices) + 1 < g.slices, d[1:], d[:-1])
    pad = (PAD * scale + PAD_ABS)[None, None, :, None]
    return lo - pad, hi + pad


def _grown(lo: np.ndarray, hi: np.ndarray, fraction: float) -> tuple[np.ndarray, np.ndarray]:
    """The box grown (fraction > 0) or shrunk by ``fraction`` of its largest finite coordinate."""
    mag = np.where(np.abs(lo) < 1e29, np.abs(lo), 0).max(axis=-1, keepdims=True)
    mag = np.maximum(mag, np.where(np.abs(hi) < 1e29, np.abs(hi), 0).max(axis=-1, keepdims=True))
    return lo - fraction * mag, hi + fraction * mag


def light_table(scene, frame: int = 0) -> dict[str, np.ndarray]:
    """Per light (float64): type, view-space centre, radius, view-space spot axis, cone cosines."""
    cam = scene.camera(frame)
    rot = cam.view[:3, :3]
    lights = scene.lights
    return {
        "type": np.array([li.type for li in lights], dtype=np.int64),
        "centre": np.array([rot @ (li.position - cam.position) for li in lights]).reshape(-1, 3),
        "world": np.array([li.position - cam.position for li in lights]).reshape(-1, 3),
        "radius": np.array([max(li.radius, LIGHT_MIN_RADIUS) for li in lights]),
        "axis": np.array([rot @ li.direction for li in lights]).reshape(-1, 3),
        "world_axis": np.array([li.direction for li in lights]).reshape(-1, 3),
        "cos_inner": np.array([li.cos_inner for li in lights]),
        "cos_outer": np.array([li.cos_outer for li in lights]),
        "radiance": np.array([li.radiance for li in lights]).reshape(-1, 3),
        "to_light": np.array([-li.direction for li in lights]).reshape(-1, 3),
    }


def touches(lights: dict[str, np.ndarray], lo: np.ndarray, hi: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """(froxels..., lights) bool: assign.comp's test; ``margin`` > 0 grows spheres, cones and
    froxels by that fraction, < 0 shrinks them."""
    lo, hi = _grown(lo, hi, margin) if margin else (lo, hi)  # a negative fraction shrinks
    c = lights["centre"]
    r = lights["radius"] * (1 + margin)
    q = np.clip(c, lo[..., None, :], hi[..., None, :]) - c
    hit = np.sum(q * q, axis=-1) <= r * r
    spot = lights["type"] == LIGHT_SPOT
    if spot.any():
        sr = 0.5 * np.linalg.norm(hi - lo, axis=-1)[..., None] * (1 + margin)
        v = 0.5 * (lo + hi)[..., None, :] - c
        v1 = np.sum(v * lights["axis"], axis=-1)
        cos_o = lights["cos_outer"]
        sin_o = np.sqrt(np.maximum(1 - cos_o * cos_o, 0))
        closest = cos_o * np.sqrt(np.maximum(np.sum(v * v, axis=-1) - v1 * v1, 0)) - v1 * sin_o
        cone = ~((closest > sr) | (v1 < -sr)) | (sr > 1e15)
        hit &= np.where(spot, cone, True)
    return hit | (lights["type"] == LIGHT_DIRECTIONAL)


def light_falloff(dist2: np.ndarray, radius: np.ndarray) -> np.ndarray:
    x = dist2 / np.maximum(radius, LIGHT_MIN_RADIUS) ** 2
    return np.clip(1 - x * x, 0, 1) ** 2 / np.maximum(dist2, 1e-6)


def spot_factor(cos_angle: np.ndarray, cos_inner: np.ndarray, cos_outer: np.ndarray) -> np.ndarray:
    t = np.clip((cos_angle - cos_outer) / np.maximum(cos_inner - cos_outer, 1e-4), 0, 1)
    return t * t


def shade(lights: dict[str, np.ndarray], world: np.ndarray, normal: np.ndarray, base_color, roughness, metallic,
          ambient, emissive=(0, 0, 0)) -> np.ndarray:
    """forward.frag over every light at camera-relative points ``world`` (..., 3): hdr rgb."""
    s = brdf.make_surface(normal, -world, normal, base_color, roughness, metallic)
    diffuse = np.zeros(world.shape)
    specular = np.zeros(world.shape)
    for k in range(len(lights["type"])):
        if lights["type"][k] == LIGHT_DIRECTIONAL:
            ldir = brdf.safe_normalize(np.broadcast_to(lights["to_light"][k], world.shape), s["n"])
            radiance = np.broadcast_to(lights["radiance"][k], world.shape)
        else:
            d = lights["world"][k] - world
            dist2 = np.sum(d * d, axis=-1)
            ldir = brdf.safe_normalize(d, s["n"])
            f = light_falloff(dist2, lights["radius"][k])
            if lights["type"][k] == LIGHT_SPOT:
                f = f * spot_factor(np.sum(ldir * -lights["world_axis"][k], axis=-1), lights["cos_inner"][k],
                                    lights["cos_outer"][k])
            radiance = lights["radiance"][k] * f[..., None]
        di, sp = brdf.eval_light(s, ldir, radiance)
        diffuse += di
        specular += sp
    return brdf.hdr_clamp(diffuse + specular + s["diffuse_color"] * np.asarray(ambient) + np.asarray(emissive))
