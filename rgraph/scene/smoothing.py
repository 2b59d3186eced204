"""Smoothed vertex normals and tangents of a deforming mesh: the topology and the float64 reference.

A mesh split at UV seams has several vertices at one surface point (one per UV chart). Its
``smooth_group`` (``MeshData.smooth_group``) maps every vertex to the representative vertex
of its smoothing group: vertices of one group share one normal, accumulated over every
triangle incident to any of them, so a seam split leaves the normals exactly as the welded
mesh had them. Without a map every vertex is its own group (``vertex_normals``' result).

The rule (the GPU pass ``shaders/scene/deform_normals.comp`` computes the same, in float32,
from the same ``SmoothingTopology``):

- face vector ``f = (p1 - p0) x (p2 - p0)`` (length twice the area; zero-area faces add 0);
- normal of group g: ``a = sum f`` over the group's triangles, ascending triangle index
  (a fixed order: the GPU sum is reproducible); unit ``a`` unless ``|a| <= REL * sum |f|``
  (no area, or faces cancelling to rounding noise), then the vertex's fallback (rest) normal;
- tangent of vertex v, over v's own triangles (its UV chart): ``t_f = (e1 dv2 - e2 dv1) sgn(r)``
  and ``b_f = (e2 du1 - e1 du2) sgn(r)``, ``r = du1 dv2 - du2 dv1`` (UV-area weighted; faces
  without UV area add 0); ``t = T - n (n.T)`` made unit unless ``|t| <= REL * |T|`` (then a
  unit vector perpendicular to n from the axis least aligned with it); the tangent's w is
  -1 when ``(n x t).B < 0``, else +1 (the bitangent's handedness).

Positions are scaled by ``scale`` (a power of two from the rest extent, exact in floats)
before any product, so float32 neither overflows for huge meshes nor underflows for tiny
ones; the results do not depend on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REL = 1e-5  # |sum f| <= REL * sum |f|: the faces cancel (or there are none): fallback


@dataclass(frozen=True)
class SmoothingTopology:
    """Per vertex its group (a representative vertex id); per group a CSR list of incident
    triangles (``offsets[g]:offsets[g + 1]`` of ``triangles``, ascending; groups are indexed by
    their representative vertex, other slots are empty)."""

    group: np.ndarray  # (n,) uint32
    offsets: np.ndarray  # (n + 1,) uint32
    triangles: np.ndarray  # (k,) uint32
    scale: float  # power of two: positions * scale are about unit size

    @property
    def vertex_count(self) -> int:
        return len(self.group)


def pow2_scale(positions: np.ndarray) -> float:
    """A power of two that brings the extent of ``positions`` near 1 (1.0 for an empty or flat one)."""
    p = np.asarray(positions, dtype=np.float64)
    if not len(p):
        return 1.0
    extent = float(np.max(np.abs(p - p.mean(axis=0)))) if np.isfinite(p).all() else 0.0
    if extent <= 0.0:
        return 1.0
    return float(2.0 ** -np.clip(np.round(np.log2(extent)), -120, 120))


def build_topology(vertex_count: int, indices: np.ndarray, smooth_group: np.ndarray | None = None,
                   rest_positions: np.ndarray | None = None) -> SmoothingTopology:
    """The CSR adjacency group -> incident triangles (each triangle once per group)."""
    n = int(vertex_count)
    idx = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    group = np.arange(n, dtype=np.int64) if smooth_group is None else np.asarray(smooth_group, dtype=np.int64)
    if group.shape != (n,) or (n and (group.min() < 0 or group.max() >= n)):
        raise ValueError("smooth_group: one representative vertex index per vertex")
    if n and not np.array_equal(group[group], group):
        raise ValueError("smooth_group: a representative must be its own group's representative")
    tri = np.repeat(np.arange(len(idx), dtype=np.int64), 3)
    pairs = np.unique(np.stack([group[idx.reshape(-1)], tri], axis=1), axis=0) if len(idx) else np.zeros((0, 2), np.int64)
    counts = np.bincount(pairs[:, 0], minlength=n) if len(pairs) else np.zeros(n, dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.uint32)
    scale = pow2_scale(rest_positions) if rest_positions is not None else 1.0
    return SmoothingTopology(group.astype(np.uint32), offsets, pairs[:, 1].astype(np.uint32), scale)


def _perpendicular(n: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to each unit row of ``n`` (from the axis least aligned with it)."""
    axis = np.where((np.abs(n[:, 0]) < 0.9)[:, None], np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    t = axis - n * np.einsum("ij,ij->i", n, axis)[:, None]
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def smooth_normals(positions: np.ndarray, indices: np.ndarray, topology: SmoothingTopology,
                   fallback: np.ndarray) -> np.ndarray:
    """The reference normals alone ((n, 3) float64, equal to ``normals_tangents``' first result)."""
    return _normals(positions, indices, topology, fallback)[0]


def _normals(positions: np.ndarray, indices: np.ndarray, topology: SmoothingTopology,
             fallback: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(normals, indices (m, 3), scaled edges e1, e2 (m, 3)) by the rule of the module docstring."""
    p = np.asarray(positions, dtype=np.float64) * topology.scale
    idx = np.asarray(indices, dtype=np.int64).reshape(-1, 3)
    n = len(p)
    fallback = np.asarray(fallback, dtype=np.float64).reshape(n, 3)
    tri = topology.triangles.astype(np.int64)
    rows = np.repeat(np.arange(n), np.diff(topology.offsets.astype(np.int64)))
    corners = p[idx]
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    face = np.cross(e1, e2)
    mag = np.linalg.norm(face, axis=1)
    acc = np.stack([np.bincount(rows, weights=face[tri, c], minlength=n) for c in range(3)], axis=1)
    total = np.bincount(rows, weights=mag[tri], minlength=n)
    length = np.linalg.norm(acc, axis=1)
    ok = (length > REL * total) & (total > 0)
    group_normal = np.where(ok[:, None], acc / np.where(ok, length, 1.0)[:, None], 0.0)
    g = topology.group.astype(np.int64)
    normals = np.where(ok[g][:, None], group_normal[g], fallback)
    return normals, idx, e1, e2


def normals_tangents(positions: np.ndarray, indices: np.ndarray, topology: SmoothingTopology,
                     fallback: np.ndarray, uvs: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The reference: (normals (n, 3), tangents (n, 4)) in float64 by the rule of the module docstring."""
    normals, idx, e1, e2 = _normals(positions, indices, topology, fallback)
    n = len(normals)
    # tangents: each vertex's own triangles
    uv = np.zeros((n, 2)) if uvs is None else np.asarray(uvs, dtype=np.float64).reshape(n, 2)
    tuv = uv[idx]
    d1, d2 = tuv[:, 1] - tuv[:, 0], tuv[:, 2] - tuv[:, 0]
    r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    sign = np.sign(r)[:, None]
    tf = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * sign
    bf = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * sign
    own = np.unique(np.stack([idx.reshape(-1), np.repeat(np.arange(len(idx)), 3)], axis=1), axis=0) \
        if len(idx) else np.zeros((0, 2), np.int64)
    big_t = np.stack([np.bincount(own[:, 0], weights=tf[own[:, 1], c], minlength=n) for c in range(3)], axis=1)
    big_b = np.stack([np.bincount(own[:, 0], weights=bf[own[:, 1], c], minlength=n) for c in range(3)], axis=1)
    t = big_t - normals * np.einsum("ij,ij->i", normals, big_t)[:, None]
    t_len, big_len = np.linalg.norm(t, axis=1), np.linalg.norm(big_t, axis=1)
    t_ok = (t_len > REL * big_len) & (big_len > 0)
    tangent = np.where(t_ok[:, None], t / np.where(t_ok, t_len, 1.0)[:, None], _perpendicular(normals))
    w = np.where(np.einsum("ij,ij->i", np.cross(normals, tangent), big_b) < 0, -1.0, 1.0)
    return normals, np.concatenate([tangent, w[:, None]], axis=1)
