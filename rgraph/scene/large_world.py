"""Large-world precision study: camera-relative float64 -> float32 vs naive float32 world transforms.

The camera sits ``distance`` metres from the origin with a small scene (vertices 0.2 .. 3 m
away) around it. Three ways to project each vertex to pixels:

- reference: float64 with the exact camera-relative offset (``position - camera`` of two
  float64 values this close is exact, Sterbenz), then float64 matrices;
- camera-relative (what rgraph does): model translation ``position - camera`` formed in
  float64, then the model matrix, the rotation-only view-projection and the vertices are
  cast to float32 and multiplied in float32 (the GPU's arithmetic);
- naive: float32 world model matrix and float32 view matrix with the camera translation,
  multiplied in float32;
- naive float64: the same world-space matrices in float64 (CPU-side double precision is not
  enough by itself either: 1e12 m has a float64 spacing of 1.2e-4 m).

``study()`` returns one row per distance: the largest pixel error of each method against
the reference (inf when a projected vertex lands at w <= 0 or is not finite).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgraph.scene.camera import model_matrix, perspective, view_rotation
from rgraph.scene.shapes import sphere

DISTANCES = (1e4, 1e6, 1e8, 1e10, 1e12)


@dataclass(frozen=True)
class Row:
    distance: float
    relative_px: float  # camera-relative float32, max pixel error
    naive_px: float  # naive float32 world transform, max pixel error
    naive64_px: float  # naive float64 world transform, max pixel error
    vertices: int


def _pixels(clip: np.ndarray, width: int, height: int) -> np.ndarray:
    clip = np.asarray(clip, dtype=np.float64)
    w = clip[:, 3:4]
    bad = ~np.isfinite(clip).all(axis=1, keepdims=True) | (w <= 0)
    ndc = clip[:, :2] / np.where(bad, 1.0, w)
    return np.where(bad, np.inf, (ndc * 0.5 + 0.5) * np.array([width, height]))


def _scene_offsets(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Object placements relative to the camera (in front of it, along -Z of its view) and
    their rotations (degrees)."""
    rng = np.random.default_rng(seed)
    n = 12
    depth = rng.uniform(0.2, 3.0, n)
    lateral = rng.uniform(-0.25, 0.25, (n, 2)) * depth[:, None]
    offsets = np.stack([lateral[:, 0], lateral[:, 1], -depth], axis=1)
    return offsets, rng.uniform(0, 360, (n, 3))


def project_vertices(distance: float, *, width: int = 1920, height: int = 1080, fov_y: float = 45.0,
                     near: float = 0.01, seed: int = 0) -> dict[str, np.ndarray]:
    """Pixel positions (k, 2) of the study scene by each method: reference, relative, naive."""
    direction = np.array([0.6, 0.48, 0.64])
    camera = direction / np.linalg.norm(direction) * distance
    forward = np.array([-0.3, -0.1, -1.0])
    view_rot = view_rotation(forward)
    proj = perspective(fov_y, width / height, near)
    offsets_view, rotations = _scene_offsets(seed)
    # offsets were drawn in view space: turn them into world offsets
    offsets = offsets_view @ view_rot[:3, :3]
    mesh = sphere(0.05, 12, 6)
    v64 = np.concatenate([mesh.positions, np.ones((mesh.vertex_count, 1))], axis=1)
    v32 = v64.astype(np.float32)
    view_world = view_rot.copy()
    view_world[:3, 3] = -view_rot[:3, :3] @ camera
    ref, rel, naive, naive64 = [], [], [], []
    for off, rot in zip(offsets, rotations, strict=True):
        world_pos = camera + off  # the object's world position, float64
        m_world = model_matrix(world_pos, rot, 1.0)
        m_rel = model_matrix(world_pos - camera, rot, 1.0)  # exact difference
        ref.append(v64 @ (proj @ view_rot @ m_rel).T)
        naive64.append(v64 @ (proj @ view_world @ m_world).T)
        # camera-relative: translation formed in float64, matrices cast to float32
        m_rel32 = m_rel.astype(np.float32)
        vp32 = (proj @ view_rot).astype(np.float32)
        world32 = v32 @ m_rel32.T
        rel.append(world32 @ vp32.T)
        # naive: float32 world matrices
        mw32, vw32, p32 = m_world.astype(np.float32), view_world.astype(np.float32), proj.astype(np.float32)
        naive.append(((v32 @ mw32.T) @ vw32.T) @ p32.T)
    return {"reference": _pixels(np.concatenate(ref), width, height),
            "relative": _pixels(np.concatenate(rel), width, height),
            "naive": _pixels(np.concatenate(naive), width, height),
            "naive64": _pixels(np.concatenate(naive64), width, height)}


def study(distances=DISTANCES, **kwargs) -> list[Row]:
    """Max pixel error of camera-relative and naive float32 transforms at each distance."""
    rows = []
    for d in distances:
        px = project_vertices(float(d), **kwargs)
        err = {k: float(np.abs(px[k] - px["reference"]).max()) for k in ("relative", "naive", "naive64")}
        rows.append(Row(float(d), err["relative"], err["naive"], err["naive64"], len(px["reference"])))
    return rows


def format_table(rows: list[Row]) -> str:
    lines = [f"{'distance (m)':>14} {'camera-relative f32 px':>24} {'naive f32 px':>14} {'naive f64 px':>14}"]
    for r in rows:
        lines.append(f"{r.distance:>14.0e} {r.relative_px:>24.2e} {r.naive_px:>14.3g} {r.naive64_px:>14.3g}")
    return "\n".join(lines)
