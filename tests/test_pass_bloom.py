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
@pytest.mark.parametrize("params", [{}, {"bloom.knee": 0.0, "bloom.radius": 2, "bloom.threshold": 0.5}],
                         ids=["defaults", "hard-threshold-r2"])
def test_bright_and_blur_stages_match_reference(params):
    hdr = _scene(2)
    out = run_graph("bloom_stages", (W, H), {"hdr": hdr}, params)
    threshold, knee = params.get("bloom.threshold", 1.0), params.get("bloom.knee", 0.5)
    bright = bloom_ref.bright(hdr, (QW, QH), threshold, knee)
    assert out["bloom_a"].shape == (QH, QW, 4)
    assert within(out["bloom_a"], bright, bloom_ref.RTOL, bloom_ref.ATOL) <= 1.0
    assert (out["bloom_a"][..., :3] > 0).any() and (out["bloom_a"][..., :3] == 0).any()  # thresholding acts
    # blur the GPU's own bright image, so each stage is checked on its own
    blurred = bloom_ref.blur(out["bloom_a"], "h", params.get("bloom.radius", 4))
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

    from rgraph.compile.pipeline import compile_graph
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / "bloom_stages.yaml", size=(16, 16))
    blur = next(p for p in plan["passes"] if p["name"] == "bloom_blur_h")
    blur["params"].pop("bloom.direction")
    with pytest.raises(ExecutionError, match="bloom.direction must be 'h' or 'v'"):
        execute_plan(plan, inputs={"hdr": np.zeros((16, 16, 4), np.float32)})
