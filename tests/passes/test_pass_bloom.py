"""The bloom chain (bright pass with Karis average, separable blur, additive combine) on
lavapipe vs the NumPy reference, including NaN locality and HDR16 overflow."""

from __future__ import annotations

import numpy as np
import pytest
from post_helpers import half, run_graph, within
from rgraph.passes import bloom_ref
from rgraph.passes.post_common_ref import HALF_MAX

W, H = 64, 48
QW, QH = W // 4, H // 4
INF, NAN = np.inf, np.nan


def _scene(seed: int) -> np.ndarray:
    """Half-float radiance: a dim background, a few bright blobs above the threshold."""
    rng = np.random.default_rng(seed)
    hdr = np.ones((H, W, 4))
    hdr[..., :3] = rng.uniform(0.0, 0.9, (H, W, 3))
    yy, xx = np.mgrid[0:H, 0:W]
    for cy, cx, peak in ((12, 16, 6.0), (30, 44, 20.0), (40, 8, 2.5)):
        hdr[..., :3] += peak * np.exp(-((yy - cy) ** 2 + (xx - cx) ** 2) / 18.0)[..., None] * rng.uniform(0.5, 1, 3)
    return half(hdr)


# ----------------------------------------------------------------------------- reference alone
def test_karis_average_tames_a_firefly():
    block = np.zeros((4, 4, 4))
    block[1, 2, :3] = INF  # one firefly; sanitized to bloom.clamp (65504)
    a = bloom_ref.bright(block, (1, 1), threshold=0.0, knee=0.0)[0, 0, :3]
    w1 = 1.0 / (1.0 + HALF_MAX)
    assert a == pytest.approx(np.full(3, HALF_MAX * w1 / (w1 + 15)), rel=1e-3)  # about 1/15, not 65504/16
    assert (a < 0.07).all()


def test_bright_threshold_and_knee():
    flat = lambda v: np.full((4, 4, 4), v)  # noqa: E731
    assert bloom_ref.bright(flat(0.4), (1, 1), 1.0, 0.5)[0, 0, :3].tolist() == [0, 0, 0]  # below the knee
    hard = bloom_ref.bright(flat(3.0), (1, 1), 1.0, 0.0)[0, 0, 0]
    assert hard == pytest.approx(2.0, rel=1e-3)  # (br - threshold) / br * a
    soft = bloom_ref.bright(flat(0.9), (1, 1), 1.0, 0.5)[0, 0, 0]
    assert 0 < soft < 0.9 and bloom_ref.bright(flat(0.9), (1, 1), 1.0, 0.0)[0, 0, 0] == 0


def test_blur_weights_and_constant_image():
    for r in (0, 1, 4, 28):
        w = bloom_ref.gaussian_weights(r)
        assert w[0] + 2 * w[1:].sum() == pytest.approx(1.0) and (np.diff(w) <= 0).all()
    img = np.full((5, 7, 4), 3.0)
    assert np.allclose(bloom_ref.blur(img, "h", 4), 3.0) and np.allclose(bloom_ref.blur(img, "v", 4), 3.0)
    with pytest.raises(ValueError, match="bloom.radius"):
        bloom_ref.gaussian_weights(29)


def test_reference_chain_keeps_a_nan_local():
    hdr = _scene(1)
    hdr[20, 30, :3] = NAN
    out = bloom_ref.chain(hdr, (QW, QH))
    assert all(np.isfinite(out[k]).all() for k in ("bright", "blur_h", "bloom"))
    bad = ~np.isfinite(out["hdr"]).all(axis=-1)
    assert np.argwhere(bad).tolist() == [[20, 30]]


# ----------------------------------------------------------------------------- on the device
@pytest.mark.vulkan
@pytest.mark.parametrize("params", [{}, {"bloom.knee": 0.0, "bloom.radius": 8, "bloom.threshold": 0.5}],
                         ids=["defaults", "hard-threshold-r8"])
def test_bright_and_blur_stages_match_reference(params):
    hdr = _scene(2)
    out = run_graph("bloom_stages", (W, H), {"hdr": hdr}, params)
    threshold, knee = params.get("bloom.threshold", 1.0), params.get("bloom.knee", 0.5)
    bright = bloom_ref.bright(hdr, (QW, QH), threshold, knee)
    assert out["bloom_a"].shape == (QH, QW, 4)
    assert within(out["bloom_a"], bright, bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    assert (out["bloom_a"][..., :3] > 0).any() and (out["bloom_a"][..., :3] == 0).any()  # thresholding acts
    # blur the GPU's own bright image, so each stage is checked on its own
    taps, sigma = bloom_ref.working_blur(params.get("bloom.radius", 16), None, 4)
    assert (taps, sigma) == ((4, 2.0) if not params else (2, 1.0))  # HDR pixels / 4
    blurred = bloom_ref.blur(out["bloom_a"], "h", taps, sigma)
    assert within(out["bloom_b"], blurred, bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0


@pytest.mark.vulkan
def test_chain_matches_reference_and_a_nan_stays_local():
    hdr = _scene(3)
    hdr[20, 30, :3] = NAN
    hdr[5, 50, 1] = NAN  # one NaN channel makes the whole texel black for the bright pass
    out = run_graph("bloom_chain", (W, H), {"hdr": hdr}, {"bloom.intensity": 0.2})
    ref = bloom_ref.chain(hdr, (QW, QH), intensity=0.2)
    for name in ("bloom_a", "bloom_b"):
        assert np.isfinite(out[name]).all(), name
    assert within(out["bloom_a"], ref["bloom"], bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    assert within(out["hdr"], ref["hdr"], bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    bad = ~np.isfinite(out["hdr"]).all(axis=-1)
    assert sorted(map(tuple, np.argwhere(bad))) == [(5, 50), (20, 30)]  # the NaN texels only
    assert (out["hdr"][..., :3] >= hdr[..., :3] - 1e-6)[~bad].all()  # bloom only adds light


@pytest.mark.vulkan
def test_chain_with_hdr16_overflow_stays_finite_outside_overflow():
    hdr = _scene(4)
    hdr[0:8, 0:8, :3] = HALF_MAX  # a saturated half-float patch
    hdr[30, 10, :3] = INF
    hdr[31, 11, 0] = -INF
    hdr[40:44, 40:44, :3] = 65000.0
    hdr = half(hdr)
    out = run_graph("bloom_chain", (W, H), {"hdr": hdr})
    ref = bloom_ref.chain(hdr, (QW, QH))
    for name in ("bloom_a", "bloom_b"):
        assert np.isfinite(out[name]).all() and out[name].max() <= HALF_MAX, name
    assert within(out["bloom_a"], ref["bloom"], bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    # the firefly's block is averaged, not exploded: far below a plain box filter's 65504/16
    assert out["bloom_a"][30 // 4 - 1:30 // 4 + 2, 10 // 4 - 1:10 // 4 + 2, :3].max() < 1.0
    assert within(out["hdr"], ref["hdr"], bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    overflowed = np.isinf(ref["hdr"])  # float16 sums past 65504 (and +-Inf inputs): the GPU may store Inf or the max
    assert overflowed[:8, :8, :3].all()
    assert (np.abs(out["hdr"][overflowed]) >= HALF_MAX).all()
    assert (np.sign(out["hdr"][overflowed]) == np.sign(ref["hdr"][overflowed])).all()
    new_bad = ~np.isfinite(out["hdr"]) & np.isfinite(hdr) & ~overflowed
    assert not new_bad.any()


@pytest.mark.vulkan
def test_blur_without_direction_is_a_clear_error():
    from post_helpers import GRAPHS

    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / "bloom_stages.yaml", size=(16, 16))
    blur = next(p for p in plan["passes"] if p["name"] == "bloom_blur_h")
    blur["params"].pop("bloom.direction")
    with pytest.raises(ExecutionError, match="bloom.direction must be 'h' or 'v'"):
        execute_plan(plan, inputs={"hdr": np.zeros((16, 16, 4), np.float32)})


# ----------------------------------------------------------------------------- bloom.scale


def test_working_blur_divides_hdr_pixels_by_the_factor():
    assert bloom_ref.working_blur(16, None, 4) == (4, 2.0)
    assert bloom_ref.working_blur(16, None, 1) == (16, 8.0)
    assert bloom_ref.working_blur(16, 6.0, 2) == (8, 3.0)
    assert bloom_ref.working_blur(10, None, 4) == (3, 1.25)  # 2.5 rounds half up


def test_full_resolution_chain_is_the_2d_gaussian_convolution():
    """At factor 1 the bright pass is per texel and blur h then v equals the 2D Gaussian
    (clamp to edge), up to the float16 rounding between the passes."""
    hdr = _scene(5)
    radius, sigma = 8, 3.0
    out = bloom_ref.chain(hdr, (W, H), threshold=0.0, knee=0.0, radius=radius, sigma=sigma)
    np.testing.assert_array_equal(out["bright"][..., :3], half(hdr[..., :3]))  # Karis over one texel
    g = np.exp(-np.arange(-radius, radius + 1) ** 2 / (2 * sigma * sigma))
    kernel = np.outer(g, g) / np.outer(g, g).sum()
    src = np.asarray(out["bright"], np.float64)
    conv = np.zeros_like(src)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            ys, xs = np.clip(np.arange(H) + dy, 0, H - 1), np.clip(np.arange(W) + dx, 0, W - 1)
            conv += kernel[dy + radius, dx + radius] * src[ys][:, xs]
    assert within(out["bloom"][..., :3], conv[..., :3], 2e-3, 1e-4) <= 1.0


def test_quarter_resolution_approximates_the_full_resolution_filter():
    """Radius and sigma in HDR pixels: the quarter-size bloom approximates the full-size one;
    the same taps in quarter texels (the old meaning) would be a 4x wider filter."""
    hdr = _scene(6)
    full = bloom_ref.chain(hdr, (W, H), intensity=1.0)["hdr"] - hdr
    quarter = bloom_ref.chain(hdr, (QW, QH), intensity=1.0)["hdr"] - hdr
    wider = bloom_ref.chain(hdr, (QW, QH), radius=64, intensity=1.0)["hdr"] - hdr

    def rel(a: np.ndarray) -> float:
        return float(np.linalg.norm((a - full)[..., :3]) / np.linalg.norm(full[..., :3]))

    assert rel(quarter) < 0.35 and rel(quarter) < rel(wider) / 3  # 0.23 vs 0.87 here


@pytest.mark.vulkan
def test_chain_at_full_resolution_matches_reference():
    hdr = _scene(7)
    params = {"bloom.scale": 1, "bloom.radius": 10, "bloom.intensity": 0.2}
    out = run_graph("bloom_chain", (W, H), {"hdr": hdr}, params)
    ref = bloom_ref.chain(hdr, (W, H), radius=10, intensity=0.2)
    assert out["bloom_a"].shape == (H, W, 4)
    assert within(out["bloom_b"], ref["blur_h"], bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    assert within(out["bloom_a"], ref["bloom"], bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    assert within(out["hdr"], ref["hdr"], bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    assert (out["bloom_a"][..., :3] > 0).any()


@pytest.mark.vulkan
def test_bright_pass_at_factor_1_is_per_texel():
    hdr = _scene(8)
    out = run_graph("bloom_stages", (W, H), {"hdr": hdr}, {"bloom.scale": 1, "bloom.threshold": 0, "bloom.knee": 0})
    assert within(out["bloom_a"][..., :3], hdr[..., :3], 1e-3, 1e-4) <= 1.0
