"""Procedural shapes: closed, consistently outward, unit normals, no degenerate faces, deterministic."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from rgraph.scene.shapes import CLOSED_SHAPES, SHAPES, MeshData, make_shape, safe_normalize, vertex_normals

SMALL = {"sphere": {"segments": 12, "rings": 6}, "neck": {"segments": 24, "stacks": 8},
         "blob": {"segments": 12, "rings": 6}, "torus": {"segments": 16, "sides": 8}}


def welded_edges(mesh: MeshData) -> Counter:
    """Directed edges over welded vertex positions."""
    keys = np.round(mesh.positions, 9)
    _, weld = np.unique(keys, axis=0, return_inverse=True)
    tri = weld.reshape(-1)[mesh.indices.astype(np.int64)]
    edges = Counter()
    for a, b, c in tri:
        for u, v in ((a, b), (b, c), (c, a)):
            edges[(int(u), int(v))] += 1
    return edges


def face_normals(mesh: MeshData) -> tuple[np.ndarray, np.ndarray]:
    p = mesh.positions[mesh.indices.astype(np.int64)]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return cross, np.linalg.norm(cross, axis=1) / 2


@pytest.mark.parametrize("shape", CLOSED_SHAPES)
def test_closed_shapes_are_watertight_and_outward(shape):
    mesh = make_shape(shape, SMALL.get(shape, {}))
    edges = welded_edges(mesh)
    # every directed edge once, and its reverse once: closed, manifold, consistently wound
    assert all(n == 1 for n in edges.values()), shape
    assert all((v, u) in edges for (u, v) in edges), shape
    p = mesh.positions[mesh.indices.astype(np.int64)]
    volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6
    assert volume > 0  # outward winding encloses positive volume


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_normals_unit_outward_and_faces_not_degenerate(shape):
    mesh = make_shape(shape, SMALL.get(shape, {}))
    assert mesh.positions.dtype == np.float64 and mesh.indices.dtype == np.uint32
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-12)
    cross, area = face_normals(mesh)
    scale = np.ptp(mesh.positions, axis=0).max()
    assert area.min() > 1e-8 * scale ** 2, "degenerate triangle"
    # vertex normals agree with the winding of every face that uses them
    vn = mesh.normals[mesh.indices.astype(np.int64)]
    agree = np.einsum("ij,ikj->ik", cross, vn)
    assert (agree > 0).all(), f"{shape}: {(agree <= 0).sum()} vertex normals disagree with their faces"
    assert mesh.indices.max() < mesh.vertex_count


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_shapes_are_deterministic(shape):
    a, b = make_shape(shape, SMALL.get(shape, {})), make_shape(shape, SMALL.get(shape, {}))
    for x, y in ((a.positions, b.positions), (a.normals, b.normals), (a.indices, b.indices)):
        assert np.array_equal(x, y)


def test_seed_changes_blob_and_sizes_follow_params():
    a, b = make_shape("blob", {"segments": 12, "rings": 6}, seed=1), make_shape("blob", {"segments": 12, "rings": 6}, seed=2)
    assert not np.array_equal(a.positions, b.positions)
    lo, hi = make_shape("box", {"size": [1, 2, 3]}).bounds()
    np.testing.assert_allclose(hi - lo, [1, 2, 3])
    lo, hi = make_shape("cylinder", {"radius": 0.5, "height": 2}).bounds()
    np.testing.assert_allclose(hi[1] - lo[1], 2)
    lo, hi = make_shape("capsule", {"radius": 0.25, "height": 1}).bounds()
    np.testing.assert_allclose(hi[1] - lo[1], 1.5)


def test_plane_faces_up_and_unknown_params_are_errors():
    plane = make_shape("plane", {"size": [2, 2], "subdivisions": 3})
    assert np.all(plane.normals == [0, 1, 0])
    cross, _ = face_normals(plane)
    assert np.all(cross[:, 1] > 0)
    with pytest.raises(ValueError, match="unknown parameter"):
        make_shape("sphere", {"radius": 1, "wobble": 2})
    with pytest.raises(ValueError, match="unknown shape"):
        make_shape("teapot")
    with pytest.raises(ValueError, match="thickness"):
        make_shape("tube", {"radius": 0.1, "thickness": 0.2})


def test_normalize_of_zero_vectors_is_finite():
    v = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 4.0], [1e-300, 0, 0]])
    n = safe_normalize(v)
    assert np.isfinite(n).all()
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    # a zero-area triangle adds nothing; a vertex used only by it takes the fallback
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 2, 2], [2, 2, 2], [2, 2, 2]], dtype=float)
    idx = np.array([[0, 1, 2], [3, 4, 5]])
    fallback = np.tile([1.0, 0, 0], (6, 1))
    n = vertex_normals(pos, idx, fallback)
    assert np.isfinite(n).all()
    np.testing.assert_allclose(n[:3], [[0, 0, 1]] * 3)
    np.testing.assert_allclose(n[3:], fallback[3:])
