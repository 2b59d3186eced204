"""NumPy float64 reference of the compute visibility buffer (passes/raytrace_visbuffer.py): per
pixel, the nearest triangle its camera ray (shaders/rt/shade.glsl: camera_ray) hits at t > 0,
as a visibility id ((instance << bits) | primitive) + 1, 0 where it hits nothing. Brute force
over every triangle: for the small test scenes only."""

from __future__ import annotations

import numpy as np

from .raytrace_visbuffer import triangle_starts
from .rt_model import build_tables


def pixel_directions(tables, size: tuple[int, int]) -> np.ndarray:
    """(h * w, 3) unnormalized camera-ray directions, row-major."""
    w, h = size
    x, y = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    sx = (2.0 * x / w - 1.0) * tables.tan_half_fov * (w / h)
    sy = (1.0 - 2.0 * y / h) * tables.tan_half_fov
    right, up, fwd = tables.basis
    return (fwd + sx[..., None] * right + sy[..., None] * up).reshape(-1, 3)


def visibility_reference(data, size: tuple[int, int], bits: int, chunk: int = 128,
                         seconds: float | None = None) -> np.ndarray:
    """(h, w) uint32 ids; ties in t go to the larger id, as the GPU's atomicMax (``seconds``:
    the deformable meshes' scene time, ``build_tables``)."""
    tables = build_tables(data, seconds)
    tris = tables.triangles.astype(np.float64)  # (n, 3, 3) camera-relative world, instance-major
    starts = triangle_starts(data).astype(np.int64)
    instance = np.searchsorted(starts, np.arange(len(tris)), side="right") - 1
    ids = ((instance << bits) | (np.arange(len(tris)) - starts[instance])) + 1
    d = pixel_directions(tables, size)
    best_t = np.full(len(d), np.inf)
    best = np.zeros(len(d), dtype=np.int64)
    for lo in range(0, len(tris), chunk):
        p0, p1, p2 = (tris[lo:lo + chunk, i][None] for i in range(3))  # (1, c, 3)
        e1, e2 = p1 - p0, p2 - p0
        dd = d[:, None]                      # (p, 1, 3)
        q = np.cross(dd, e2)                 # (p, c, 3)
        det = (e1 * q).sum(-1)
        s = -p0                              # ray origin 0 - p0
        r = np.cross(s, e1)                  # (1, c, 3)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            u = (s * q).sum(-1) * inv
            v = (dd * r).sum(-1) * inv
            t = (e2 * r).sum(-1) * inv
        hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        t = np.where(hit, t, np.inf)
        chunk_ids = ids[lo:lo + chunk][None]
        # nearest in the chunk, ties to the larger id; then against the best so far
        key = np.where(hit, chunk_ids, -1)
        tmin = t.min(axis=1)
        cand = np.where(t == tmin[:, None], key, -1).max(axis=1)
        better = (tmin < best_t) | ((tmin == best_t) & (cand > best) & np.isfinite(tmin))
        best_t = np.where(better, tmin, best_t)
        best = np.where(better, cand, best)
    w, h = size
    return np.where(np.isfinite(best_t), best, 0).astype(np.uint32).reshape(h, w)


def edge_pixels(ids: np.ndarray) -> np.ndarray:
    """Pixels whose id differs from one of their 8 neighbours' (triangle or silhouette edges)."""
    padded = np.pad(ids, 1, mode="edge")
    h, w = ids.shape
    out = np.zeros(ids.shape, dtype=bool)
    for dy in range(3):
        for dx in range(3):
            out |= padded[dy:dy + h, dx:dx + w] != ids
    return out
