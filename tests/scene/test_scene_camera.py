"""Camera matrices (float64, camera-relative) vs an independent float64 reference; shadow fits."""

from __future__ import annotations

import numpy as np
import pytest

from rgraph.scene.camera import (
    camera_state,
    euler_rotation,
    model_matrix,
    orthonormal_basis,
    perspective,
    shadow_view_proj,
    view_rotation,
)


def reference_look_at(eye, target, up):
    """Classic right-handed world -> view (with translation), written out independently."""
    z = np.asarray(eye, float) - np.asarray(target, float)
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = x, y, z
    m[:3, 3] = -m[:3, :3] @ np.asarray(eye, float)
    return m


def test_view_projection_matches_reference_and_depth_is_reversed_infinite():
    eye, target = np.array([1.0, 2.0, 5.0]), np.array([0.2, 0.1, -0.3])
    cam = camera_state(eye, target, [0, 1, 0], 50.0, 0.05, 16 / 9)
    rng = np.random.default_rng(3)
    pts = target + rng.normal(size=(50, 3))
    world_to_view = reference_look_at(eye, target, np.array([0.0, 1.0, 0.0]))
    view_ref = (np.c_[pts, np.ones(50)] @ world_to_view.T)[:, :3]
    view_rel = (pts - eye) @ cam.view[:3, :3].T
    np.testing.assert_allclose(view_rel, view_ref, atol=1e-12)
    # projection: x, y as a standard perspective with Vulkan's downward Y; depth = near / -z
    f = 1 / np.tan(np.radians(25))
    clip = np.c_[view_ref, np.ones(50)] @ cam.proj.T
    ndc = clip[:, :3] / clip[:, 3:]
    np.testing.assert_allclose(ndc[:, 0], f / (16 / 9) * view_ref[:, 0] / -view_ref[:, 2], rtol=1e-12)
    np.testing.assert_allclose(ndc[:, 1], -f * view_ref[:, 1] / -view_ref[:, 2], rtol=1e-12)
    np.testing.assert_allclose(ndc[:, 2], 0.05 / -view_ref[:, 2], rtol=1e-12)
    # the look-at point lands at the centre; near plane -> depth 1; far away -> 0
    c = cam.view_proj @ np.append(target - eye, 1)
    np.testing.assert_allclose(c[:2] / c[3], 0, atol=1e-12)
    near_pt = cam.proj @ np.array([0, 0, -0.05, 1])
    assert near_pt[2] / near_pt[3] == pytest.approx(1.0)
    far_pt = cam.proj @ np.array([0, 0, -1e30, 1])
    assert 0 <= far_pt[2] / far_pt[3] < 1e-30
    np.testing.assert_allclose(cam.inv_view_proj @ cam.view_proj, np.eye(4), atol=1e-9)
    np.testing.assert_allclose(cam.inv_view @ cam.view, np.eye(4), atol=1e-12)


def test_float32_cast_of_camera_relative_matrices_is_accurate():
    cam = camera_state([1e7, 2.0, -3e6], [1e7 + 1.0, 1.5, -3e6 - 2.0], [0, 1, 0], 40.0, 0.01, 1.5)
    m = model_matrix(np.array([1e7 + 0.7, 1.8, -3e6 - 1.1]) - cam.position, (10, 20, 30), 0.5)
    v = np.array([0.1, -0.2, 0.05, 1.0])
    exact = cam.view_proj @ m @ v
    f32 = cam.view_proj.astype(np.float32) @ (m.astype(np.float32) @ v.astype(np.float32))
    np.testing.assert_allclose(f32[:2] / f32[3], exact[:2] / exact[3], atol=1e-6)


def test_euler_order_and_orthonormal_rotations():
    r = euler_rotation((90, 0, 0))
    np.testing.assert_allclose(r @ [0, 1, 0], [0, 0, 1], atol=1e-15)  # Rx(90): +Y -> +Z
    r = euler_rotation((90, 90, 0))
    np.testing.assert_allclose(r @ [0, 1, 0], [1, 0, 0], atol=1e-15)  # X first, then Y
    r = euler_rotation((13, -71, 200))
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(r) == pytest.approx(1.0)
    v = view_rotation([0.3, -0.2, -1])
    np.testing.assert_allclose(v[:3, :3] @ v[:3, :3].T, np.eye(3), atol=1e-14)


@pytest.mark.parametrize("direction", [(0, -1, 0), (0, 1, 0), (0, -1, 1e-9), (1e-12, -1, 0)])
def test_light_parallel_to_up_has_a_finite_basis_and_shadow_matrix(direction):
    r, u, f = orthonormal_basis(direction)
    for a in (r, u, f):
        assert np.isfinite(a).all() and abs(np.linalg.norm(a) - 1) < 1e-12
    assert abs(r @ u) < 1e-12 and abs(r @ f) < 1e-12 and abs(u @ f) < 1e-12
    pts = np.array([[x, y, z] for x in (-1, 2) for y in (-0.5, 0.5) for z in (-3, 1)], dtype=float)
    m = shadow_view_proj(direction, pts)
    assert np.isfinite(m).all()
    clip = np.c_[pts, np.ones(len(pts))] @ m.T
    assert np.all(np.abs(clip[:, :2]) <= 1) and np.all((clip[:, 2] >= 0) & (clip[:, 2] <= 1))


def test_shadow_depth_is_reversed_one_nearest_the_light():
    pts = np.array([[0, 0, 0], [0, -1, 0], [1, 1, 1], [-1, -2, -1]], dtype=float)
    m = shadow_view_proj((0, -1, 0), pts)  # light travels down: the highest point is nearest
    depth = (np.c_[pts, np.ones(4)] @ m.T)[:, 2]
    assert depth[2] > depth[0] > depth[1] > depth[3]
    assert 0.9 < depth[2] <= 1 and 0 <= depth[3] < 0.1


def test_perspective_aspect():
    p = perspective(90, 2.0, 0.1)
    assert p[0, 0] == pytest.approx(0.5) and p[1, 1] == pytest.approx(-1.0)
