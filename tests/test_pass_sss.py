"""Separable SSS (sss_blur as sss_blur_h and sss_blur_v) against the NumPy float64 reference.

Tolerance: each direction within 2e-3 absolute + 2e-3 relative of the reference run on
that pass's actual (fp16) input: the output is fp16 (half an ulp is 5e-4 relative) and the
GPU's bilinear filtering and float32 weights add less than that. Zero SSS strength or zero
width must be the identity bit for bit; a constant image must stay constant.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rgraph.passes import sss_ref as ref
from rgraph.passes.screenspace_ref import Camera, render_depth

from rgraph.compile.pipeline import compile_graph

GRAPHS = Path(__file__).parent / "pass_graphs"
FOV, NEAR = 40.0, 0.01


def camera(w: int, h: int) -> Camera:
    return Camera(fov_y=FOV, near=NEAR, aspect=w / h)


def inputs(w: int, h: int, seed: int = 1, strength: float = 0.8):
    """A skin sphere in front of a wall: depth, random fp16 colour, normal_sss (a = strength on the sphere)."""
    cam = camera(w, h)
    depth = render_depth(w, h, cam, planes=[((0, 0, -0.5), (0, 0, 1))], spheres=[((0.01, 0.0, -0.3), 0.06)])
    depth = depth.astype(np.float32).astype(np.float64)
    color = np.float16(np.random.default_rng(seed).uniform(0, 2, (h, w, 4))).astype(np.float64)
    nsss = np.zeros((h, w, 4))
    nsss[..., :3] = 0.5
    nsss[..., 3] = np.where(depth > NEAR / 0.45, np.round(strength * 255) / 255, 0.0)
    return depth, color, nsss


def run(size, depth, color, nsss, params):
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / "sss.yaml", size=size, params={k: str(v) for k, v in params.items()})
    result = execute_plan(plan, validate=True, read_outputs=True,
                          inputs={"depth": depth[..., None], "diffuse": color, "normal_sss": nsss})
    assert [m.text for m in result.messages] == []
    for name in ("sss_tmp", "diffuse"):
        assert np.all(np.isfinite(result.outputs[name])), name
    return {k: np.asarray(result.outputs[k], np.float64) for k in ("sss_tmp", "diffuse")}


def close(got, want):
    return np.all(np.abs(got - want) <= 2e-3 + 2e-3 * np.abs(want))


# ----------------------------------------------------------------------------- NumPy only


@pytest.mark.parametrize("samples", ref.SAMPLE_COUNTS)
def test_kernel_sums_to_one_per_channel(samples):
    for strength in (ref.SKIN_STRENGTH, (1.0, 1.0, 1.0), (0.0, 0.5, 0.2)):
        k = ref.kernel(samples, strength)
        np.testing.assert_allclose(k[:, :3].sum(axis=0), 1.0, atol=1e-12)
        assert k[0, 3] == 0.0 and np.all(k[:, :3] >= 0)
        np.testing.assert_allclose(np.sort(k[:, 3]), -np.sort(k[:, 3])[::-1], atol=1e-12)  # symmetric offsets
    assert abs(np.abs(ref.kernel(samples)[:, 3]).max() - (3.0 if samples > 20 else 2.0)) < 1e-12


def test_red_scatters_farther_than_blue():
    k = ref.kernel(25, (1.0, 1.0, 1.0))
    spread = (k[:, :3] * k[:, 3:4] ** 2).sum(axis=0)  # second moment per channel
    assert spread[0] > spread[1] > 0 and spread[0] > spread[2]


def test_reference_identity_and_follow_surface():
    w, h = 48, 32
    cam = camera(w, h)
    depth, color, nsss = inputs(w, h)
    kw = dict(p00=cam.p00, p11=cam.p11, near=NEAR)
    zero = nsss.copy()
    zero[..., 3] = 0
    for d, n, s in ((depth, zero, ref.SSSSettings(width=0.05)), (depth, nsss, ref.SSSSettings(width=0.0))):
        assert np.array_equal(ref.reference(color, d, n[..., 3], settings=s, **kw)["diffuse"], color)
    # two surfaces far apart in depth, side by side: follow-surface keeps them from mixing
    depth2 = np.where(np.arange(w) < w // 2, NEAR / 0.3, NEAR / 0.4)[None].repeat(h, 0)
    color2 = np.where((np.arange(w) < w // 2)[None, :, None], 1.0, 0.0) * np.ones((h, w, 4))
    a = np.full((h, w), 1.0)
    out = ref.blur(color2, depth2, a, direction="h", settings=ref.SSSSettings(width=0.05), **kw)
    bleed = ref.blur(color2, depth2, a, direction="h", settings=ref.SSSSettings(width=0.05, follow_depth=1e3), **kw)
    far = np.r_[0 : w // 2 - 3, w // 2 + 3 : w]  # bilinear taps straddle the edge only next to it
    np.testing.assert_allclose(out[:, far], color2[:, far], atol=1e-12)
    assert np.abs(bleed - color2).max() > 5 * np.abs(out - color2).max()


# ----------------------------------------------------------------------------- lavapipe


@pytest.mark.vulkan
@pytest.mark.parametrize("samples", ref.SAMPLE_COUNTS)
def test_sss_matches_reference(samples):
    w, h = 64, 48
    cam = camera(w, h)
    depth, color, nsss = inputs(w, h)
    settings = ref.SSSSettings(samples=samples, width=0.03)
    out = run((w, h), depth, color, nsss, {"sss.samples": samples, "sss.width": 0.03})
    kw = dict(p00=cam.p00, p11=cam.p11, near=NEAR, settings=settings)
    want_h = ref.blur(color, depth, nsss[..., 3], direction="h", **kw)
    assert close(out["sss_tmp"], want_h)
    assert np.abs(want_h - color).max() > 0.1  # it really blurs
    want_v = ref.blur(out["sss_tmp"], depth, nsss[..., 3], direction="v", **kw)
    assert close(out["diffuse"], want_v)
    skin = nsss[..., 3] > 0
    assert np.array_equal(out["diffuse"][~skin], color[~skin])  # non-SSS pixels untouched


@pytest.mark.vulkan
@pytest.mark.parametrize("case", ["zero_strength", "zero_width"])
def test_zero_sss_is_exactly_the_identity_on_gpu(case):
    w, h = 40, 24
    depth, color, nsss = inputs(w, h, strength=0.0 if case == "zero_strength" else 0.8)
    out = run((w, h), depth, color, nsss, {"sss.width": 0.0 if case == "zero_width" else 0.05})
    assert np.array_equal(out["sss_tmp"], color) and np.array_equal(out["diffuse"], color)


@pytest.mark.vulkan
@pytest.mark.parametrize("samples", ref.SAMPLE_COUNTS)
def test_constant_image_stays_constant_on_gpu(samples):
    """Kernel weights sum to one per channel on the GPU too: flat depth, constant colour."""
    w, h = 40, 24
    depth = np.full((h, w), NEAR / 0.3)
    color = np.ones((h, w, 4)) * np.float16([0.7, 1.3, 0.2, 1.0])
    nsss = np.ones((h, w, 4))
    out = run((w, h), depth, color, nsss, {"sss.samples": samples, "sss.width": 0.05})
    np.testing.assert_allclose(out["diffuse"], color, rtol=1e-3, atol=0)
    np.testing.assert_allclose(out["sss_tmp"], color, rtol=1e-3, atol=0)
