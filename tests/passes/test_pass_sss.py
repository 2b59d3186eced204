"""Separable SSS (sss_blur as sss_blur_h and sss_blur_v) against the NumPy float64 reference.

Tolerance: each direction within 2e-3 absolute + 2e-3 relative of the reference run on
that pass's actual (fp16) input: the output is fp16 (half an ulp is 5e-4 relative) and the
GPU's bilinear filtering and float32 weights add less than that. Zero SSS strength or zero
width must be the identity bit for bit; a constant image must stay constant.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rgraph.passes import sss_ref as ref
from rgraph.passes.screenspace_ref import Camera, render_depth

from rgraph.compiler.pipeline import compile_graph

GRAPHS = TESTS / "pass_graphs"
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


# ----------------------------------------------------------------------------- sss.kernel = 2d


def disc_inputs(n: int = 64, z: float = 0.3):
    """A small bright disc (radially symmetric) on a flat, fully-SSS surface facing the camera."""
    yy, xx = np.mgrid[0:n, 0:n] + 0.5
    r = np.hypot(xx - n / 2, yy - n / 2)
    color = np.zeros((n, n, 4))
    color[..., 3] = 1.0
    color[..., :3] = np.where(r < 2.5, 4.0, 0.0)[..., None]
    depth = np.full((n, n), np.float32(NEAR / z)).astype(np.float64)
    nsss = np.ones((n, n, 4))
    return depth, color, nsss, r, np.degrees(np.arctan2(yy - n / 2, xx - n / 2)) % 90


def diagonal_over_axis(img: np.ndarray, r: np.ndarray, angle: np.ndarray, lo: float = 5, hi: float = 9) -> np.ndarray:
    """Per channel: mean over the ring lo <= r < hi near the diagonals / near the axes (1 = isotropic)."""
    ring = (r >= lo) & (r < hi)
    diag, axis = ring & (np.abs(angle - 45) < 12), ring & ((angle < 12) | (angle > 78))
    return np.array([img[..., c][diag].mean() / img[..., c][axis].mean() for c in range(3)])


@pytest.mark.parametrize("samples", ref.SAMPLE_COUNTS)
def test_2d_kernel_is_normalized_symmetric_and_radial(samples):
    k = ref.kernel_2d(samples)
    np.testing.assert_allclose(k[:, :3].sum(axis=0), 1.0, atol=1e-12)
    assert k[0, 3] == k[0, 4] == 0.0 and np.all(k[:, :3] >= 0)
    assert np.hypot(k[:, 3], k[:, 4]).max() <= ref.kernel_range(samples) + 1e-9  # a disc
    taps = {(round(x, 9), round(y, 9)): tuple(w) for *w, x, y in k.tolist()}
    for (x, y), w in taps.items():  # invariant under the 8 symmetries of the grid
        for mirror in ((y, x), (-x, y), (x, -y)):
            np.testing.assert_allclose(taps[mirror], w, rtol=1e-12)
    # weight / cell area depends on r only: the profile itself
    offsets, cells = ref._offsets_and_cells(samples)
    cell = {round(o, 9): c for o, c in zip(offsets, cells, strict=True)}
    unblended = k.copy()
    s = np.asarray(ref.SKIN_STRENGTH)
    unblended[1:, :3] /= s
    density = unblended[1:, :3] / np.array([cell[round(x, 9)] * cell[round(y, 9)] for x, y in k[1:, 3:5]])[:, None]
    want = np.array([ref.profile(np.hypot(x, y)) for x, y in k[1:, 3:5]])
    ratio = density / want
    np.testing.assert_allclose(ratio, np.broadcast_to(ratio[0], ratio.shape), rtol=1e-9)


def test_2d_reference_is_isotropic_where_the_separable_pair_is_not():
    """On a radially symmetric input the 2D blur stays (nearly) radially symmetric; the
    separable pair puts far more light along the axes than along the diagonals (its strength
    blend runs once per direction, leaving one-axis blurs, and k(x) k(y) is not the profile)."""
    depth, color, nsss, r, angle = disc_inputs()
    cam = camera(64, 64)
    settings = ref.SSSSettings(samples=25, width=0.1, follow_depth=1.0)
    kw = dict(p00=cam.p00, p11=cam.p11, near=NEAR, settings=settings)
    separable = ref.reference(color, depth, nsss[..., 3], **kw)["diffuse"]
    two_d = ref.reference(color, depth, nsss[..., 3], **{**kw, "settings": ref.SSSSettings(
        samples=25, width=0.1, follow_depth=1.0, kernel="2d")})["diffuse"]
    assert np.all(np.abs(diagonal_over_axis(two_d, r, angle) - 1.0) < 0.1)
    assert np.all(diagonal_over_axis(separable, r, angle) < 0.3)


@pytest.mark.vulkan
@pytest.mark.parametrize("samples", [11, 25])
def test_2d_kernel_on_gpu_matches_reference_and_differs_from_separable(samples):
    n = 64
    depth, color, nsss, r, angle = disc_inputs(n)
    cam = camera(n, n)
    params = {"sss.samples": samples, "sss.width": 0.1, "sss.follow_depth": 1.0}
    two_d = run((n, n), depth, color, nsss, {**params, "sss.kernel": "2d"})
    separable = run((n, n), depth, color, nsss, params)
    settings = ref.SSSSettings(samples=samples, width=0.1, follow_depth=1.0, kernel="2d")
    want = ref.blur_2d(color, depth, nsss[..., 3], p00=cam.p00, p11=cam.p11, near=NEAR, settings=settings)
    assert close(two_d["sss_tmp"], want)
    assert np.array_equal(two_d["diffuse"], two_d["sss_tmp"])  # the v pass is a copy
    assert not close(separable["diffuse"], want)
    # the 2D grid is coarse in the profile's tail at 11 samples (ratio 0.75 there, 1.0-1.04 at 25)
    assert np.all(np.abs(diagonal_over_axis(two_d["diffuse"], r, angle) - 1.0) < (0.1 if samples == 25 else 0.3))
    assert np.all(diagonal_over_axis(separable["diffuse"], r, angle) < 0.3)


@pytest.mark.vulkan
def test_2d_kernel_matches_reference_on_a_sphere_with_follow_surface():
    w, h = 48, 32
    cam = camera(w, h)
    depth, color, nsss = inputs(w, h)
    out = run((w, h), depth, color, nsss, {"sss.kernel": "2d", "sss.samples": 17, "sss.width": 0.03})
    settings = ref.SSSSettings(samples=17, width=0.03, kernel="2d")
    want = ref.blur_2d(color, depth, nsss[..., 3], p00=cam.p00, p11=cam.p11, near=NEAR, settings=settings)
    assert close(out["diffuse"], want) and np.abs(want - color).max() > 0.1
    skin = nsss[..., 3] > 0
    assert np.array_equal(out["diffuse"][~skin], color[~skin])


def test_unknown_kernel_is_refused():
    with pytest.raises(ValueError, match="sss.kernel"):
        ref.SSSSettings.from_params({"sss.kernel": "3d"})
