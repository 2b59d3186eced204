"""Sweep metrics on synthetic arrays: PSNR, SSIM (Wang et al. 2004), HDR metrics, FLIP."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rgraph.sweep import flip, metrics
from rgraph.sweep.compare import Images, compare

C1 = (0.01 * 1.0) ** 2
C2 = (0.03 * 1.0) ** 2


def _image(seed: int = 0, shape=(40, 48, 3)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.random(shape)


def _noisy(image: np.ndarray, sigma: float, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.clip(image + rng.normal(0.0, sigma, image.shape), 0.0, 1.0)


def test_psnr_identical_is_inf_and_known_value():
    a = _image()
    assert metrics.psnr(a, a.copy()) == math.inf
    zeros = np.zeros((8, 8, 3))
    assert metrics.psnr(zeros, zeros + 0.1) == pytest.approx(20.0)
    assert metrics.psnr(zeros, zeros + 0.5, peak=0.5) == pytest.approx(0.0, abs=1e-12)


def test_ssim_identical_is_one():
    a = _image()
    assert metrics.ssim(a, a.copy()) == pytest.approx(1.0, abs=1e-12)


def test_ssim_of_constant_images_is_the_luminance_term():
    # no variance: contrast-structure term is C2/C2 = 1, luminance term is exact
    a, b = np.full((20, 20), 0.2), np.full((20, 20), 0.4)
    want = (2 * 0.2 * 0.4 + C1) / (0.2**2 + 0.4**2 + C1)
    assert metrics.ssim(a, b) == pytest.approx(want, rel=1e-9)


def _ssim_window_brute_force(x: np.ndarray, y: np.ndarray, top: int, left: int) -> float:
    taps = metrics.gaussian_window(11, 1.5)
    w = np.outer(taps, taps)
    px, py = x[top:top + 11, left:left + 11], y[top:top + 11, left:left + 11]
    mx, my = (w * px).sum(), (w * py).sum()
    vx, vy = (w * (px - mx) ** 2).sum(), (w * (py - my) ** 2).sum()
    cxy = (w * (px - mx) * (py - my)).sum()
    return ((2 * mx * my + C1) * (2 * cxy + C2)) / ((mx**2 + my**2 + C1) * (vx + vy + C2))


def test_ssim_map_matches_the_formula_window_by_window():
    x = _image(3, (24, 30))
    y = _noisy(x, 0.1)
    ssim_map = metrics.ssim_map(x, y)
    assert ssim_map.shape == (24 - 10, 30 - 10)  # 'valid' region of the 11x11 window
    for top, left in [(0, 0), (5, 7), (13, 19)]:
        assert ssim_map[top, left] == pytest.approx(_ssim_window_brute_force(x, y, top, left), rel=1e-9)
    assert metrics.ssim(x, y) == pytest.approx(float(ssim_map.mean()), rel=1e-12)


def test_gaussian_window_is_normalized_and_symmetric():
    taps = metrics.gaussian_window()
    assert len(taps) == 11 and taps.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(taps, taps[::-1])
    assert taps.argmax() == 5


def test_ssim_uses_luminance():
    a = _image(4)
    swapped = a[..., ::-1]  # same pixels, red and blue swapped: different luma
    assert metrics.ssim(a, swapped) < 1.0
    grey = np.repeat(a[..., :1], 3, axis=-1)
    assert metrics.ssim(grey, grey[..., :1]) == pytest.approx(1.0)  # one channel = its own luma


def test_ssim_small_images_shrink_the_window():
    a = _image(5, (6, 9, 3))
    assert metrics.ssim(a, a) == pytest.approx(1.0)
    assert metrics.ssim_map(a[..., 0], a[..., 0]).shape == (2, 5)  # window 5 (odd, <= 6)


def test_errors_grow_with_noise():
    a = _image(6, (48, 48, 3))
    sigmas = [0.01, 0.03, 0.1, 0.3]
    psnrs = [metrics.psnr(a, _noisy(a, s)) for s in sigmas]
    ssims = [metrics.ssim(a, _noisy(a, s)) for s in sigmas]
    assert psnrs == sorted(psnrs, reverse=True) and len(set(psnrs)) == 4
    assert ssims == sorted(ssims, reverse=True) and len(set(ssims)) == 4
    hdr = a * 8.0
    rel = [metrics.rel_mse(hdr, hdr + s * 8.0 * (_image(7, a.shape) - 0.5)) for s in sigmas]
    assert rel == sorted(rel)


def test_shapes_must_match():
    with pytest.raises(ValueError, match="differ in shape"):
        metrics.psnr(np.zeros((4, 4, 3)), np.zeros((4, 5, 3)))
    with pytest.raises(ValueError, match="differ in shape"):
        metrics.ssim(np.zeros((12, 12)), np.zeros((12, 13)))


def test_hdr_metrics_known_values():
    r, t = np.ones((4, 4, 3)), np.full((4, 4, 3), 2.0)
    assert metrics.rel_mse(r, t) == pytest.approx(1.0 / 1.01)
    assert metrics.rel_mse(r, r) == 0.0
    assert metrics.log_psnr(r, r) == math.inf
    # log2(1 + 1) = 1, log2(1 + 3) = 2: MSE 1, peak max(1, 1) = 1 -> 0 dB
    assert metrics.log_psnr(r, t + 1.0) == pytest.approx(0.0, abs=1e-12)


def test_srgb_round_trip():
    x = np.linspace(0, 1, 101)
    np.testing.assert_allclose(metrics.linear_to_srgb(metrics.srgb_to_linear(x)), x, atol=1e-12)
    assert metrics.linear_to_srgb(np.array([0.5]))[0] == pytest.approx(0.7354, abs=1e-4)


@pytest.mark.skipif(not flip.available(), reason="flip-evaluator not installed")
def test_flip_identical_is_zero_and_grows_with_noise():
    a = _image(8, (32, 32, 3))
    error_map, mean = flip.flip_ldr(a, a.copy())
    assert mean == 0.0 and error_map.shape == (32, 32)
    means = [flip.flip_ldr(a, _noisy(a, s))[1] for s in (0.02, 0.1, 0.3)]
    assert 0.0 < means[0] < means[1] < means[2] <= 1.0
    magma, _ = flip.flip_ldr(a, _noisy(a, 0.1), magma=True)
    assert magma.shape == (32, 32, 3)
    assert flip.flip_hdr(a * 4, a * 4) == 0.0
    assert flip.missing_note() is None


def test_without_flip_the_rest_still_works(monkeypatch):
    monkeypatch.setattr(flip, "_module", lambda: None)
    assert flip.flip_ldr(np.zeros((4, 4, 3)), np.ones((4, 4, 3))) is None
    assert "pip install flip-evaluator" in flip.missing_note()
    a = _image(9, (16, 16, 3))
    values, notes = compare(Images(a, a * 3), Images(_noisy(a, 0.1), a * 3))
    assert values["flip"] is None and values["hdr_flip"] is None and notes == []
    assert values["psnr"] < math.inf and values["ssim"] < 1.0 and values["hdr_rel_mse"] == 0.0


def test_compare_notes_size_mismatch():
    values, notes = compare(Images(np.zeros((8, 8, 3)), None), Images(np.zeros((4, 8, 3)), None))
    assert values["psnr"] is None and "differs" in notes[0]
