"""NumPy float64 reference of box-projected deferred decals (``passes/decals.py``); no Vulkan.

Per pixel with geometry (depth > 0): the camera-relative world position from depth and the
inverse view-projection; for each decal in scene order, its box-local position
``world_to_decal @ world``; a decal covers the pixel when every local coordinate is within
[-0.5, 0.5]. Its coverage ``a = opacity * facing_fade * depth_fade`` with
``facing_fade = saturate((|n . z_axis| - 0.25) * 4)`` (n: the world normal from
``normal_sss.rgb``, z_axis: the normalized world gradient of local z, the projection axis;
surfaces seen edge-on by the projector get no decal) and
``depth_fade = saturate((0.5 - |local z|) * 10)`` (soft ends of the projection).
Its colour is lit like a diffuse surface: ``colour.rgb * (ambient + sun_radiance *
max(n . to_sun, 0) / pi)`` (the Frame's ``ambient``, ``sun_radiance``, ``sun_direction``).

Blending (decided): premultiplied "over" (alpha blending) in decal order, then over the
target: ``diffuse = C + (1 - A) diffuse``, ``specular = (1 - A) specular``,
``alpha = A + (1 - A) alpha`` for both targets, with ``C, A`` the composited decal colour and
coverage. A decal is a matte film: it hides the surface's lighting beneath it in proportion
to its coverage and replaces the diffuse by its own; its own specular is not modelled.
Normals are never written.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .screenspace_ref import pixel_uv


@dataclass(frozen=True)
class DecalBox:
    world_to_decal: np.ndarray  # 4x4, camera-relative world -> box [-0.5, 0.5]^3
    color: tuple[float, float, float, float]  # rgb, opacity


def world_positions(depth: np.ndarray, inv_view_proj: np.ndarray) -> np.ndarray:
    """(h, w, 3) camera-relative world positions (NaN-free only where depth > 0)."""
    d = np.asarray(depth, np.float64)
    h, w = d.shape
    ndc = 2.0 * pixel_uv(w, h) - 1.0
    clip = np.stack([ndc[..., 0], ndc[..., 1], d, np.ones_like(d)], axis=-1)
    world = clip @ np.asarray(inv_view_proj, np.float64).T
    with np.errstate(divide="ignore", invalid="ignore"):
        return world[..., :3] / world[..., 3:4]


def reference(depth: np.ndarray, normal_sss: np.ndarray, diffuse: np.ndarray, specular: np.ndarray, *,
              inv_view_proj: np.ndarray, decals: list[DecalBox], to_sun: np.ndarray, sun_radiance: np.ndarray,
              ambient: np.ndarray) -> dict[str, np.ndarray]:
    """``diffuse``, ``specular`` after the pass, ``coverage`` (A) and ``edge`` (pixels within
    1e-4 of a box face in x or y, where float32 may decide inside/outside differently)."""
    d = np.asarray(depth, np.float64).reshape(np.shape(depth)[:2])
    geo = d > 0
    world = world_positions(np.where(geo, d, 1.0), inv_view_proj)
    n = np.asarray(normal_sss, np.float64)[..., :3] * 2.0 - 1.0
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.where(length > 1e-3, n / np.maximum(length, 1e-30), 0.0)
    light = (np.asarray(ambient, np.float64)
             + np.asarray(sun_radiance, np.float64) * np.maximum(n @ np.asarray(to_sun, np.float64), 0.0)[..., None]
             / math.pi)
    color = np.zeros(d.shape + (3,))
    alpha = np.zeros(d.shape)
    edge = np.zeros(d.shape, bool)
    for box in decals:
        m = np.asarray(box.world_to_decal, np.float64)
        local = world @ m[:3, :3].T + m[:3, 3]
        inside = geo & np.all(np.abs(local) <= 0.5, axis=-1)
        edge |= geo & np.any(np.abs(np.abs(local) - 0.5) < 1e-4, axis=-1)
        axis = m[2, :3] / np.linalg.norm(m[2, :3])
        facing = np.abs(n @ axis)
        a = (box.color[3] * np.clip((facing - 0.25) * 4.0, 0.0, 1.0)
             * np.clip((0.5 - np.abs(local[..., 2])) * 10.0, 0.0, 1.0))
        a = np.where(inside, a, 0.0)
        color = np.asarray(box.color[:3], np.float64) * light * a[..., None] + color * (1.0 - a[..., None])
        alpha = a + alpha * (1.0 - a)
    diff = np.asarray(diffuse, np.float64).copy()
    spec = np.asarray(specular, np.float64).copy()
    keep = (1.0 - alpha)[..., None]
    diff[..., :3] = color + keep * diff[..., :3]
    spec[..., :3] = keep * spec[..., :3]
    diff[..., 3] = alpha + (1.0 - alpha) * diff[..., 3]
    spec[..., 3] = alpha + (1.0 - alpha) * spec[..., 3]
    return {"diffuse": diff, "specular": spec, "coverage": alpha, "edge": edge}
