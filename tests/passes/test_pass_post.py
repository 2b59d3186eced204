"""composite (hdr = diffuse + specular) and the whole post chain on lavapipe vs NumPy references."""

from __future__ import annotations

import numpy as np
import pytest
from post_helpers import half, run_graph, within
from rgraph.passes import bloom_ref, composite_ref, tonemap_ref

W, H = 32, 24


def test_composite_reference_rules():
    d = np.array([[[1.0, 60000.0, np.nan, 1.0], [np.inf, -60000.0, 2.0, 1.0]]])
    s = np.array([[[0.5, 60000.0, 1.0, 0.0], [1.0, -60000.0, -np.inf, 0.0]]])
    ref = composite_ref.reference(d, s)
    assert ref[0, 0, :2].tolist() == [1.5, 65504.0]  # a finite overflow clamps to the half range
    assert np.isnan(ref[0, 0, 2]) and ref[0, 1, 0] == np.inf and ref[0, 1, 2] == -np.inf  # non-finite passes
    assert ref[0, 1, 1] == -65504.0 and (ref[..., 3] == 1.0).all()


def _composite_inputs(seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    d = half(rng.uniform(0, 8, (H, W, 4)) ** 2)
    s = half(rng.uniform(0, 3, (H, W, 4)))
    d[0, 0, 0] = np.nan
    s[0, 1, 1] = np.inf
    d[1, 0, :3], s[1, 0, :3] = 60000.0, 60000.0  # HDR16 overflow of the sum
    d[1, 1, :3], s[1, 1, :3] = 65504.0, np.inf
    d[2, 2, :3] = -0.25  # negative radiance passes through (the tonemap clamps it)
    return d, s


@pytest.mark.vulkan
def test_composite_gpu_matches_reference():
    d, s = _composite_inputs()
    out = run_graph("post_composite", (W, H), {"diffuse": d, "specular": s})["hdr"]
    ref = composite_ref.reference(d, s)
    assert within(out, ref, composite_ref.RTOL, composite_ref.ATOL) <= 1.0
    np.testing.assert_array_equal(np.isnan(out), np.isnan(ref))
    np.testing.assert_array_equal(np.isinf(out), np.isinf(ref))
    assert out[1, 0, :3].tolist() == [65504.0] * 3 and out[1, 1, 0] == np.inf
    bad = ~np.isfinite(out[..., :3]).all(axis=-1)
    assert sorted(map(tuple, np.argwhere(bad))) == [(0, 0), (0, 1), (1, 1)]  # only the non-finite inputs


def _post_chain_reference(d: np.ndarray, s: np.ndarray) -> np.ndarray:
    hdr = composite_ref.reference(d, s)
    bloom = bloom_ref.chain(hdr, (W // 4, H // 4), threshold=1.0, intensity=0.05)
    return tonemap_ref.reference(bloom["hdr"], exposure=2.0, white=11.2)


@pytest.mark.vulkan
def test_post_chain_as_in_surgery_matches_reference_and_stays_finite():
    """composite -> bloom_bright -> blur h -> blur v -> combine -> tonemap, wired as surgery.yaml."""
    d, s = _composite_inputs(2)
    color = run_graph("post_chain", (W, H), {"diffuse": d, "specular": s})["color"]
    assert np.isfinite(color).all() and color.min() >= 0.0 and color.max() <= 1.0
    ref = _post_chain_reference(d, s)
    diff = np.abs(tonemap_ref.srgb_codes(color[..., :3]) - tonemap_ref.srgb_codes(ref[..., :3]))
    assert diff.max() <= tonemap_ref.TOLERANCE_SRGB_CODES, diff.max()  # float16 stages are mirrored
    assert color[0, 0, :3].tolist() == [0.0, 0.0, 0.0]  # the NaN texel is black
    assert color[0, 1, 1] == 1.0 and color[1, 1, :3].tolist() == [1.0, 1.0, 1.0]  # Inf is white


def test_references_import_without_vulkan():
    import subprocess
    import sys

    code = ("import sys; sys.modules['vulkan'] = None\n"
            "from rgraph.passes import bloom_ref, composite_ref, tonemap_ref, post_common_ref\n"
            "assert not any(m.startswith('rgraph.vk') for m in sys.modules), sorted(sys.modules)\n")
    subprocess.run([sys.executable, "-c", code], check=True)
