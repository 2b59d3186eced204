"""Smoothing groups across UV seams and the float64 normal/tangent reference (rgraph.scene.smoothing)."""

from __future__ import annotations

import numpy as np
import pytest

from rgraph.scene.deform import Deformer
from rgraph.scene.shapes import make_shape, vertex_normals
from rgraph.scene.smoothing import build_topology, normals_tangents, pow2_scale

SEGMENTS, STACKS = 24, 8


def welded_side(neck, positions):
    """The neck's side as one welded grid (seam copies -> column 0), caps left out."""
    n_side = SEGMENTS * (STACKS + 1)
    idx = neck.indices.astype(np.int64)
    seam = (idx >= n_side) & (idx < n_side + STACKS + 1)
    side = (idx < n_side + STACKS + 1).all(axis=1)
    return positions[:n_side], np.where(seam, (idx - n_side) * SEGMENTS, idx)[side]


def test_the_seam_split_keeps_the_welded_normals():
    neck = make_shape("neck", {"segments": SEGMENTS, "stacks": STACKS})
    assert neck.uvs is not None and neck.smooth_group is not None
    d = Deformer(neck)
    for t in (0.0, 0.85, 1.7):
        pos = d.positions(t)
        normals, tangents = normals_tangents(pos, neck.indices, d.topology, neck.normals, neck.uvs)
        wpos, widx = welded_side(neck, pos)
        n_side = len(wpos)
        np.testing.assert_allclose(normals[:n_side], vertex_normals(wpos, widx), rtol=0, atol=1e-12)
        seam = np.arange(n_side, n_side + STACKS + 1)
        assert np.array_equal(normals[seam], normals[neck.smooth_group[seam]])
        # tangents: unit, perpendicular to the normal, along +u (around the neck), right-handed
        np.testing.assert_allclose(np.linalg.norm(tangents[:, :3], axis=1), 1.0, atol=1e-12)
        assert np.abs(np.einsum("ij,ij->i", tangents[:, :3], normals)).max() < 1e-12
        assert (tangents[:n_side, 3] == 1.0).all()
        around = np.cross([0.0, 1.0, 0.0], normals[:n_side])
        assert (np.einsum("ij,ij->i", tangents[:n_side, :3], around) > 0.9).all()


def test_at_is_the_reference_and_write_positions_is_float32_of_positions():
    neck = make_shape("neck", {"segments": SEGMENTS, "stacks": STACKS})
    d = Deformer(neck)
    mesh = d.at(0.4)
    ref, _ = normals_tangents(mesh.positions, neck.indices, d.topology, neck.normals, neck.uvs)
    assert np.array_equal(mesh.normals, ref)
    out = np.empty((neck.vertex_count, 3), dtype=np.float32)
    d.write_positions(0.4, out)
    np.testing.assert_allclose(out, mesh.positions, rtol=3e-7, atol=1e-9)
    with pytest.raises(ValueError, match="C-contiguous"):
        d.write_positions(0.4, np.empty((neck.vertex_count, 6), dtype=np.float32)[:, :3])


def test_topology_checks_and_scale():
    with pytest.raises(ValueError, match="representative"):
        build_topology(3, np.array([[0, 1, 2]]), np.array([1, 2, 2]))  # 0 -> 1, but 1 -> 2
    with pytest.raises(ValueError, match="one representative"):
        build_topology(3, np.array([[0, 1, 2]]), np.array([0, 1]))
    top = build_topology(4, np.array([[0, 1, 2], [0, 0, 3]]))
    assert top.offsets.tolist() == [0, 2, 3, 4, 5] and top.triangles.tolist() == [0, 1, 0, 0, 1]
    assert pow2_scale(np.array([[1e30, 0, 0], [-1e30, 0, 0]])) * 1e30 == pytest.approx(1.0, rel=0.5)
    assert pow2_scale(np.zeros((3, 3))) == 1.0 and pow2_scale(np.zeros((0, 3))) == 1.0
