"""IBL passes on lavapipe vs their NumPy float64 references (passes/ibl_ref.py).

Tolerances:
- GPU vs the same-sample-sequence reference: |diff| <= 2e-3 + 2e-3 * |ref| for the LUT
  (float32 arithmetic, float16 storage: half-ulp 2^-11 relative), and 4e-3 relative +
  2e-3 absolute for the prefiltered environment (float16 storage of HDR radiance);
- GPU (64 samples) vs the "truth" (16384 samples, float64): <= 0.05 max, <= 0.01 mean absolute
  (the Monte Carlo error of 64 Hammersley points; at 32x32 the reference measures max/mean
  0.046/0.0050 at 64 samples, 0.031/0.0033 at 128, 0.020/0.0021 at 256, 0.010/0.0008 at 1024);
  the truth itself vs an independent hemisphere quadrature: <= 2e-3 for roughness >= 0.25.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rgraph.passes import ibl_ref

from rgraph.compiler.pipeline import compile_graph

GRAPH = TESTS / "pass_graphs" / "ibl.yaml"


def run_ibl(params: dict[str, str] | None = None, frames: int = 1):
    """(messages, {(name, mip): array}) after ``frames`` frames of the IBL test graph."""
    from rgraph.probe.semantics import mip_extent
    from rgraph.vk.executor import Executor
    from rgraph.vk.texels import decode

    plan = compile_graph(GRAPH, size=(32, 24), params=params or {})
    executor = Executor(plan, validate=True, device_index=None, verbose=False)
    try:
        executor.run_frames(frames)
        raw = executor.read_back(frames)
    finally:
        messages = executor.close()
    res = {r["name"]: r for r in plan["resources"]}
    out = {}
    for (name, mip, _layer), data in raw.items():
        w, h = mip_extent(res[name], mip)
        out[(name, mip)] = decode(res[name]["format"], data, w, h)
    return [m.text for m in messages], out, plan


def test_hammersley_matches_definition():
    pts = ibl_ref.hammersley(8)
    assert np.allclose(pts[:, 0], np.arange(8) / 8)
    assert np.allclose(pts[:, 1], [0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875])


def test_equirect_round_trip_and_onb_at_poles():
    rng = np.random.default_rng(3)
    uv = rng.uniform(0.01, 0.99, (100, 2))
    assert np.allclose(ibl_ref.equirect_uv(ibl_ref.equirect_dir(uv)), uv)
    poles = np.array([[0, 0, 1.0], [0, 0, -1.0], [0, 1.0, 0], [0, -1.0, 0], [1.0, 0, 0], [0, 1e-9, -1.0]])
    poles /= np.linalg.norm(poles, axis=-1, keepdims=True)
    t, b = ibl_ref.onb(poles)
    for x, y in ((t, b), (t, poles), (b, poles)):
        assert np.allclose(np.sum(x * y, axis=-1), 0.0, atol=1e-12)
    assert np.allclose(np.linalg.norm(t, axis=-1), 1) and np.allclose(np.linalg.norm(b, axis=-1), 1)


def test_lut_truth_agrees_with_independent_quadrature():
    truth_samples = 16384
    for nov, rough in ((0.1, 0.25), (0.5, 0.5), (0.9, 1.0), (0.3, 0.7)):
        mc = ibl_ref.brdf_lut_single(nov, rough, truth_samples)
        quad = ibl_ref.brdf_lut_quadrature(nov, rough)
        assert np.abs(mc - quad).max() <= 2e-3, (nov, rough, mc, quad)


def test_lut_smooth_limit():
    """Roughness -> minimum: A + B -> 1 with B -> (1 - N.V)^5 (a mirror with the Schlick Fresnel)."""
    nov = np.array([0.2, 0.6, 0.95])
    ab = np.array([ibl_ref.brdf_lut_single(x, 0.0, 4096) for x in nov])
    assert np.allclose(ab[:, 1], (1 - nov) ** 5, atol=0.01)
    assert np.allclose(ab.sum(axis=-1), 1.0, atol=0.03)


def test_lut_error_falls_with_samples():
    truth = ibl_ref.brdf_lut(8, 16384)
    errors = [np.abs(ibl_ref.brdf_lut(8, n) - truth).mean() for n in (16, 64, 256)]
    assert errors[0] > errors[1] > errors[2]


@pytest.mark.vulkan
def test_ibl_passes_match_references():
    messages, out, plan = run_ibl(frames=1)
    assert messages == []
    size, samples, width, mips = 16, 64, 32, 4
    lut = out[("brdf_lut", 0)]
    assert lut.shape == (size, size, 2) and np.isfinite(lut).all()
    want = ibl_ref.brdf_lut(size, samples)
    assert np.abs(lut - want).max() <= 2e-3 + 2e-3 * np.abs(want).max()
    assert np.all(np.abs(lut - want) <= 2e-3 + 2e-3 * np.abs(want))
    truth = ibl_ref.brdf_lut(size, 16384)
    assert np.abs(lut - truth).max() <= 0.05 and np.abs(lut - truth).mean() <= 0.01
    assert 1e-3 < np.abs(lut - truth).max()  # 64 samples are visibly not the truth
    levels = ibl_ref.prefilter_levels(width, width // 2, mips, samples)
    for m, ref in enumerate(levels):
        gpu = out[("env_map", m)]
        assert gpu.shape == (*ref.shape[:2], 4) and np.isfinite(gpu).all()
        np.testing.assert_allclose(gpu[..., :3], ref, rtol=4e-3, atol=2e-3, err_msg=f"env_map mip {m}")
        assert np.all(gpu[..., 3] == 1.0)
    # the mirror level is the environment itself; rougher levels are smoother (lower peak)
    peaks = [level.max() for level in levels]
    assert all(a > b for a, b in zip(peaks, peaks[1:], strict=False))


@pytest.mark.vulkan
@pytest.mark.parametrize("static", ["1", "0"])
def test_ibl_results_persist_over_frames(static):
    """Static (built in frame 0 only, zero-group dispatches after) and rebuilt-every-frame
    runs both hold the reference after 3 frames."""
    messages, out, _ = run_ibl({"ibl.static": static, "ibl.lut_size": "8", "ibl.env_mips": "2"}, frames=3)
    assert messages == []
    np.testing.assert_allclose(out[("brdf_lut", 0)], ibl_ref.brdf_lut(8, 64), atol=3e-3)
    np.testing.assert_allclose(out[("env_map", 1)][..., :3], ibl_ref.prefilter(16, 8, 1.0, 64), rtol=4e-3, atol=2e-3)
