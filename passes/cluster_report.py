"""What ``rgraph run`` says about a clustered frame: the light-list statistics and the heatmap.

``cluster_stats`` (uint32[4], written by ``light_assign``): list entries asked for (light
indices, or bitmask words with ``clusters.list=bitmask``),
overflowed froxels (shaded with every light: the image stays right, the frame slower),
longest list, list capacity. ``light_heat`` (r32_sfloat): lights shaded per pixel.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Heatmap colour ramp (Olsson's figures: blue few, red many): stops at 0, 1/4, 1/2, 3/4, 1.
RAMP = np.array([[0, 0, 96], [0, 128, 255], [0, 224, 96], [255, 224, 0], [224, 0, 0]], dtype=np.float64)


def stats_of(raw: np.ndarray | bytes) -> dict[str, int]:
    v = np.frombuffer(bytes(raw), dtype=np.uint32, count=4)
    return {"references": int(v[0]), "overflowed_froxels": int(v[1]), "longest_list": int(v[2]),
            "capacity": int(v[3])}


def stats_line(stats: dict[str, int]) -> str:
    if stats["capacity"] == 0:
        return "rgraph: light lists: not built (lighting.mode=all_lights shades every light)"
    line = (f"rgraph: light lists: {stats['references']} entries (capacity {stats['capacity']}), "
            f"longest list {stats['longest_list']} lights")
    if stats["overflowed_froxels"]:
        line += (f"; OVERFLOW: {stats['overflowed_froxels']} froxel(s) did not fit and were shaded with every "
                 f"light (raise clusters.max_indices to at least {stats['references']})")
    return line


def heat_rgba(heat: np.ndarray, scale: float | None = None) -> tuple[np.ndarray, float]:
    """(h, w) lights per pixel -> (RGBA8 image, the count mapped to the top of the ramp)."""
    h = np.asarray(heat, dtype=np.float64).reshape(heat.shape[0], heat.shape[1])
    top = float(scale if scale else max(h.max(), 1.0))
    t = np.clip(h / top, 0.0, 1.0) * (len(RAMP) - 1)
    i = np.minimum(np.floor(t).astype(int), len(RAMP) - 2)
    f = (t - i)[..., None]
    rgb = RAMP[i] * (1 - f) + RAMP[i + 1] * f
    rgb[h <= 0] = 0.0
    rgba = np.concatenate([rgb, np.full(h.shape + (1,), 255.0)], axis=-1)
    return np.round(rgba).astype(np.uint8), top


def write_heatmap(path: Path, heat: np.ndarray) -> str:
    """Write the heatmap PNG; returns a one-line description."""
    from rgraph.png import write_png

    rgba, top = heat_rgba(heat)
    write_png(Path(path), rgba)
    h = np.asarray(heat).reshape(rgba.shape[:2])
    lit = h[h > 0]
    mean = float(lit.mean()) if lit.size else 0.0
    return f"rgraph: wrote heatmap {path} (lights per pixel: mean {mean:.1f} over geometry, max {h.max():.0f}; red = {top:.0f})"
