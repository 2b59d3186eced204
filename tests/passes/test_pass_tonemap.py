"""tonemap_filmic on lavapipe vs the NumPy Hable reference, hard inputs and a golden image."""

from __future__ import annotations

import numpy as np
import pytest
from golden_images import assert_image_close, read_png, to_rgba8
from post_helpers import half, run_graph
from rgraph.passes import tonemap_ref

INF, NAN = np.inf, np.nan


def test_reference_curve_and_hard_inputs():
    white = 11.2
    ramp = np.linspace(0, 20, 200)
    mapped = tonemap_ref.reference(np.stack([ramp] * 3, -1)[None], exposure=1.0, white=white)[0, :, 0]
    assert mapped[0] == pytest.approx(0.0, abs=1e-12) and (np.diff(mapped) >= 0).all()
    assert tonemap_ref.reference(np.full((1, 1, 3), white), 1.0, white)[0, 0, 0] == pytest.approx(1.0)
    hard = np.array([[[NAN, 1, 1], [INF, 0, 0], [1e30, 1e30, 1e30], [-5, -INF, 0.5], [65504, 0, 0], [NAN, INF, -1]]])
    out = tonemap_ref.reference(hard)
    assert np.isfinite(out).all() and out.min() >= 0 and out.max() <= 1
    assert out[0, 0, :3].tolist() == [0, 0, 0] and out[0, 5, :3].tolist() == [0, 0, 0]  # NaN texel -> black
    assert out[0, 1, :3].tolist() == [1, 0, 0] and out[0, 2, :3].tolist() == [1, 1, 1]  # Inf, 1e30 -> white
    assert out[0, 3, :2].tolist() == [0, 0] and out[0, 4, 0] == 1.0
    # +Inf is white whatever the exposure; finite values follow the curve
    dim = tonemap_ref.reference(np.array([[[INF, 1e4, 1.0]]]), exposure=1e-6)
    assert dim[0, 0, 0] == 1.0 and 0 < dim[0, 0, 1] < 0.1 and dim[0, 0, 2] < 1e-4


def _codes(linear: np.ndarray) -> np.ndarray:
    return tonemap_ref.srgb_codes(linear[..., :3])


def _hdr_with_hard_cases(w: int, h: int, hard: list[list[float]], seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    hdr = np.exp(rng.uniform(-6, 4, (h, w, 4)))  # 0.0025 .. 55
    hdr[..., 3] = 1.0
    for i, rgb in enumerate(hard):
        hdr[i // w, i % w, :3] = rgb
    return hdr


HALF_HARD = [[NAN, 1, 1], [INF, 0, 0], [INF, INF, INF], [-INF, 2, 0.1], [65504, 65504, 65504], [65504, 0, 0],
             [-3, 0.5, 2], [-0.0, 0, 0], [6e-8, 6e-5, 1e-3], [NAN, NAN, NAN], [60000, 1e-4, 11.2 / 2]]


@pytest.mark.vulkan
@pytest.mark.parametrize("exposure,white", [(2.0, 11.2), (0.5, 4.0)])
def test_tonemap_gpu_matches_reference_with_hdr16_hard_cases(exposure, white):
    w, h = 32, 24
    hdr = half(_hdr_with_hard_cases(w, h, HALF_HARD, 3))
    color = run_graph("tonemap", (w, h), {"hdr": hdr}, {"tonemap.exposure": exposure, "tonemap.white": white})["color"]
    assert np.isfinite(color).all() and color.min() >= 0.0 and color.max() <= 1.0 and (color[..., 3] == 1.0).all()
    ref = tonemap_ref.reference(hdr, exposure, white)
    assert np.abs(_codes(color) - _codes(ref)).max() <= tonemap_ref.TOLERANCE_SRGB_CODES
    first = color[0, :len(HALF_HARD), :3]
    assert first[0].tolist() == [0, 0, 0] and first[9].tolist() == [0, 0, 0]  # NaN -> black
    assert first[1].tolist() == [1, 0, 0] and first[2].tolist() == [1, 1, 1]  # Inf -> white
    assert first[3, 0] == 0 and first[6, 0] == 0  # -Inf and negative radiance -> 0
    assert first[4].tolist() == [1, 1, 1]  # the largest half value saturates


@pytest.mark.vulkan
def test_tonemap_gpu_float32_radiance_beyond_half_range():
    w, h = 16, 8
    hard = [[1e30, 1e30, 1e30], [3.4e38, 0, 0], [-1e30, 1e30, 0], [1e30, NAN, 1], [1e-30, 1e-38, 0],
            [1e5, 1e6, 1e7], [INF, -INF, NAN]]
    hdr = _hdr_with_hard_cases(w, h, hard, 4).astype(np.float32)
    color = run_graph("tonemap_f32", (w, h), {"hdr": hdr})["color"]
    assert np.isfinite(color).all() and color.min() >= 0.0 and color.max() <= 1.0
    ref = tonemap_ref.reference(hdr)
    assert np.abs(_codes(color) - _codes(ref)).max() <= tonemap_ref.TOLERANCE_SRGB_CODES
    first = color[0, :len(hard), :3]
    assert first[0].tolist() == [1, 1, 1] and first[1].tolist() == [1, 0, 0] and first[2].tolist() == [0, 1, 0]
    assert first[3].tolist() == [0, 0, 0] and first[5].tolist() == [1, 1, 1] and first[6].tolist() == [0, 0, 0]


def hdr_ramp(w: int = 64, h: int = 16) -> np.ndarray:
    """A synthetic HDR test card: log-spaced radiance 2^-8..2^6 across, four tints down."""
    x = np.exp2(np.linspace(-8, 6, w))
    tints = np.array([[1, 1, 1], [1, 0.3, 0.1], [0.2, 1, 0.4], [0.3, 0.5, 1.0]])
    rows = np.repeat(tints, h // 4, axis=0)
    hdr = np.ones((h, w, 4))
    hdr[..., :3] = rows[:, None, :] * x[None, :, None]
    return half(hdr)


@pytest.mark.vulkan
def test_tonemap_golden_ramp():
    hdr = hdr_ramp()
    color = run_graph("tonemap", (64, 16), {"hdr": hdr})["color"]
    assert_image_close("tonemap_filmic_ramp", color, tolerance=1)
    # the golden itself is the reference's picture, not merely a blessed GPU output
    from golden_images import GOLDEN_DIR

    golden = read_png(GOLDEN_DIR / "tonemap_filmic_ramp.png").astype(int)
    assert np.abs(golden - to_rgba8(tonemap_ref.reference(hdr)).astype(int)).max() <= 1
