"""Skinning on lavapipe under validation + synchronization validation (zero messages):

- the GPU's posed vertices (``skin_readback``: shaders/scene/skinning.glsl, the vertex shaders'
  code) against the float64 matrix reference (passes/skinning_ref.py) of the same half-float
  logic states, at alpha 0, 0.5 and 1, for two characters with their own skeletons;
- the animation advances from one logic state to the next (frames at a 30 Hz logic rate);
- graphs/clustered.yaml draws the characters: the forward pass's depth_read test passes on every
  pixel the (skinned) depth prepass covered - the two vertex shaders pose identically - and the
  nearest depth is the nearest posed vertex's.
"""

from __future__ import annotations

import numpy as np
import pytest
from skinning_helpers import LOGIC_HZ, SIZE, clip_of
from skinning_helpers import readback_pose as _gpu
from skinning_helpers import reference_pose as _reference
from skinning_helpers import run_skinned as _run

from rgraph.scene.animation import logic_tick


@pytest.mark.vulkan
@pytest.mark.parametrize("alpha", [0.0, 0.5, 1.0])
def test_gpu_skinning_matches_the_reference(tmp_path, alpha):
    _data, mesh, out = _run(tmp_path, frames=2, params={"skin_readback.alpha": str(alpha)})
    got_p, got_n = _gpu(mesh, out)
    want_p, want_n = _reference(mesh, 1, alpha)
    assert np.abs(got_p - want_p).max() < 2e-5  # float32 of the same half inputs, ~2 m coordinates
    assert np.abs(got_n - want_n).max() < 1e-4
    rest = mesh.data.positions
    assert np.abs(got_p[0] - rest).max() > 0.05 and np.abs(got_p[0] - got_p[1]).max() > 0.05  # posed, each its own


@pytest.mark.vulkan
def test_gpu_interpolates_along_the_shortest_arc(tmp_path, monkeypatch):
    """Odd logic states store every quaternion negated (the same rotations): interpolating
    without the sign flip would swing the long way round."""
    from rgraph.scene.animation import Animator

    plain = Animator.state

    def flipped(self, tick, hz=60.0, threads=1):
        packed = plain(self, tick, hz, threads)
        if tick % 2:
            packed = packed.copy()
            packed[..., 4:8] = -packed[..., 4:8]
        return packed

    monkeypatch.setattr(Animator, "state", flipped)
    _data, mesh, out = _run(tmp_path, bones=64, frames=2)  # frame 1: states -1 (flipped) -> 0 at 0.5
    want = _reference(mesh, 1, None)[0]
    assert np.abs(_gpu(mesh, out)[0] - want).max() < 2e-5
    monkeypatch.setattr(Animator, "state", plain)
    assert np.abs(_reference(mesh, 1, None)[0] - want).max() < 1e-9  # the same poses either way


@pytest.mark.vulkan
def test_animation_advances_between_logic_states(tmp_path):
    # 30 Hz logic, 60 Hz frames: frame 1 is halfway from state -1 to 0, frame 2 is state 0 -> 1 at 0
    got = {}
    for frames in (1, 2, 3):
        _data, mesh, out = _run(tmp_path, bones=64, frames=frames)
        got[frames - 1] = _gpu(mesh, out)[0]
        want = _reference(mesh, frames - 1, None)[0]
        assert np.abs(got[frames - 1] - want).max() < 2e-5, frames
    assert logic_tick(1 / 60.0, LOGIC_HZ) == (0, pytest.approx(0.5))
    start = _reference(mesh, 0, 0.0)[0]  # state -1
    end = _reference(mesh, 0, 1.0)[0]  # state 0
    assert np.abs(end - start).max() > 1e-3  # the states differ
    # alpha 0.5 of the interpolation lies between them, not at either end
    assert np.abs(got[1] - start).max() > 1e-4 and np.abs(got[1] - end).max() > 1e-4
    assert np.allclose(got[2], end, atol=2e-5)  # frame 2 shows state 0 at alpha 0


@pytest.mark.vulkan
def test_clustered_draws_skinned_characters_without_depth_holes(tmp_path):
    _data, mesh, out = _run(tmp_path, readback=False, outputs=("depth", "hdr"), floor=False)
    depth = out["depth"].reshape(SIZE[1], SIZE[0])
    hdr = out["hdr"].reshape(SIZE[1], SIZE[0], -1)[..., :3].astype(np.float64)
    covered = depth > 0
    lit = hdr.sum(axis=-1) > 0
    assert covered.sum() > 0.03 * covered.size
    assert np.array_equal(lit, covered)  # forward's depth_read test passed on every prepass pixel
    # the nearest pixel is the nearest posed vertex (depth is affine over a screen triangle, so no
    # pixel is nearer than the nearest vertex, and a vertex facing the camera is covered)
    cam = _data.camera(0)
    world = _reference(mesh, 0, None)[0] + mesh.positions[:, None, :] - cam.position
    clip = clip_of(world, cam.view_proj)
    nearest = (clip[..., 2] / clip[..., 3]).max()
    assert nearest * 0.97 < depth.max() <= nearest * 1.0001
