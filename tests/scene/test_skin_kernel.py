"""The fast logic-state path (rgraph.scene.skin_kernel, behind ``Animator.state``) against the
reference ``pack_bones(pose)`` (``Animator.reference_state``): bit-identical half floats for
truncated and full rigs, odd character counts, threads, amplitudes and speeds, far-off scene
times, into strided outputs, and on the clamping path (translations beyond the half range);
no allocation per tick; non-finite inputs refused."""

from __future__ import annotations

import tracemalloc
from dataclasses import replace

import numpy as np
import pytest

from rgraph.scene.animation import Animator
from rgraph.scene.character import build_rig
from rgraph.scene.skin_kernel import StateKernel, supported
from rgraph.scene.skinning import HALF_MAX, Skeleton, unpack_bones


def bits(state: np.ndarray) -> np.ndarray:
    return np.asarray(state).view(np.uint16)


@pytest.mark.parametrize("bones, characters, amplitude, speed", [
    (1, 3, 1.0, 1.0), (2, 1, 1.0, 1.0), (7, 65, 2.0, 0.5), (53, 130, 1.0, 3.0), (54, 5, 0.0, 1.0),
    (255, 64, 1.0, 1.0), (256, 200, 2.5, 1.7)])
def test_kernel_states_are_bit_identical_to_the_reference(bones, characters, amplitude, speed):
    anim = Animator(build_rig(bones), characters, speed=speed, amplitude=amplitude, seed=bones)
    assert supported(anim)
    for tick in (0, 1, 37, 10_000_003):
        want = bits(anim.reference_state(tick))
        assert np.array_equal(bits(anim.state(tick)), want), tick
        assert np.array_equal(bits(anim.state(tick, 30.0)), bits(anim.reference_state(tick, 30.0)))
        assert np.array_equal(bits(anim.state(tick, threads=3)), want), tick


def test_kernel_writes_strided_outputs_and_pieces_do_not_matter():
    anim = Animator(build_rig(256), 96, seed=5)
    want = bits(anim.reference_state(11))
    wide = np.zeros((256, 200, 8), np.uint16)
    StateKernel(anim, slice(32, 80), piece=7).state(11 / 60.0, wide[:, 100:148])
    assert np.array_equal(wide[:, 100:148], want[:, 32:80])
    assert not wide[:, :100].any() and not wide[:, 148:].any()  # nothing outside the view
    for piece in (1, 16, 300):
        assert np.array_equal(StateKernel(anim, piece=piece).state(11 / 60.0), want)


def test_clamped_translations_take_the_clip_path_and_stay_identical():
    rig = build_rig(16)
    huge = replace(rig, skeleton=Skeleton(rig.skeleton.parents, rig.skeleton.heads * 1e5))
    anim = Animator(huge, 9, seed=2)
    kernel = StateKernel(anim)
    assert kernel.clip_t
    got = kernel.state(3 / 60.0)
    assert np.array_equal(got, bits(anim.reference_state(3)))
    assert np.abs(unpack_bones(got.view(np.float16)).t).max() == HALF_MAX  # some clamped
    assert not StateKernel(Animator(rig, 9)).clip_t  # the character's reach proves the clamp a no-op


def test_a_tick_allocates_nothing_that_grows_with_the_state():
    peaks = []
    for characters in (128, 512):
        anim = Animator(build_rig(256), characters, seed=1)
        out = np.empty((256, characters, 8), np.float16)
        anim.state(0, out=out)  # builds the kernel
        tracemalloc.start()
        try:
            anim.state(1, out=out)
            peaks.append(tracemalloc.get_traced_memory()[1])
        finally:
            tracemalloc.stop()
        assert np.array_equal(bits(out), bits(anim.reference_state(1)))
    assert peaks[1] < 128 * 1024 and peaks[1] <= peaks[0] * 1.25, peaks  # NumPy's iterator buffers; the state is 2 MiB


def test_non_finite_inputs_are_refused_and_float64_takes_the_reference_path():
    rig = build_rig(8)
    with pytest.raises(ValueError, match="finite"):
        StateKernel(Animator(rig, 4)).state(float("nan"))
    with pytest.raises(ValueError, match="finite"):
        Animator(rig, 4).state(1, hz=float("nan"))
    with pytest.raises(ValueError, match="amplitudes must be finite"):
        StateKernel(Animator(rig, 4, amplitude=float("inf")))
    exact = Animator(rig, 4, dtype=np.float64)
    assert not supported(exact)
    assert np.array_equal(bits(exact.state(5)), bits(exact.reference_state(5)))
    with pytest.raises(ValueError, match="float32"):
        StateKernel(exact)
