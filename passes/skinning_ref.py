"""Float64 reference of skinning (independent of rgraph.scene.skinning's vectorised path):
4x4 matrices, one bone at a time, one character at a time.

- :func:`local_matrices` / :func:`world_matrices`: the hierarchy walked bone by bone;
- :func:`skin_matrices`: world times the inverse bind (a translation by minus the rest head);
- :func:`skin_vertices`: linear-blend skinning with blended matrices;
- :func:`nlerp_matrix`: one bone between two logic states, the shortest-arc normalised lerp
  written with scalar maths (sign flip when the 4D dot product is negative).
"""

from __future__ import annotations

import math

import numpy as np


def quat_matrix(q) -> np.ndarray:
    """3x3 rotation of a unit xyzw quaternion (normalised here)."""
    x, y, z, w = (float(c) for c in q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def similarity(q, t, s) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = float(s) * quat_matrix(q)
    m[:3, 3] = np.asarray(t, dtype=np.float64)
    return m


def local_matrices(q: np.ndarray, t: np.ndarray, s: np.ndarray) -> list[np.ndarray]:
    """Per bone of one character: ``q`` (B, 4), ``t`` (B, 3), ``s`` (B,)."""
    return [similarity(q[b], t[b], s[b]) for b in range(len(s))]


def world_matrices(parents, local: list[np.ndarray]) -> list[np.ndarray]:
    out: list[np.ndarray] = []
    for b, p in enumerate(parents):
        out.append(local[b] if p < 0 else out[p] @ local[b])
    return out


def skin_matrices(heads: np.ndarray, world: list[np.ndarray]) -> list[np.ndarray]:
    out = []
    for b, m in enumerate(world):
        inv_bind = np.eye(4)
        inv_bind[:3, 3] = -np.asarray(heads[b], dtype=np.float64)
        out.append(m @ inv_bind)
    return out


def skin_vertices(positions: np.ndarray, joints: np.ndarray, weights: np.ndarray,
                  skins: list[np.ndarray]) -> np.ndarray:
    out = np.zeros((len(positions), 3))
    for v, p in enumerate(positions):
        m = sum(float(w) * skins[int(j)] for j, w in zip(joints[v], weights[v], strict=True) if w != 0)
        out[v] = (m @ np.append(p, 1.0))[:3]
    return out


def nlerp_matrix(q0, t0, s0, q1, t1, s1, alpha: float) -> np.ndarray:
    dot = sum(float(a) * float(b) for a, b in zip(q0, q1, strict=True))
    sign = -1.0 if dot < 0 else 1.0
    q = [float(a) + alpha * (sign * float(b) - float(a)) for a, b in zip(q0, q1, strict=True)]
    t = [float(a) + alpha * (float(b) - float(a)) for a, b in zip(t0, t1, strict=True)]
    return similarity(q, t, float(s0) + alpha * (float(s1) - float(s0)))
