"""NumPy float64 references of the IBL passes (``shaders/ibl/``); no Vulkan needed.

- ``env_radiance(d)``: the procedural operating-room environment, a pure function of direction;
- ``brdf_lut(size, samples)``: split-sum GGX BRDF integration (Karis 2013) with Smith
  height-correlated visibility, texel (x, y) = (N.V, roughness) at texel centres, with the
  same Hammersley sample sequence as the GPU; ``brdf_lut_quadrature`` is an independent
  deterministic integral over the light hemisphere (no importance sampling) to check it;
- ``prefilter(width, height, roughness, samples)``: one equirectangular level of ``env_map``.
"""

from __future__ import annotations

import numpy as np
from rgraph.passes.forward_ref import HDR_MAX, MIN_ROUGHNESS, ggx_alpha, v_smith_ggx_correlated

ENV_CEILING = np.array([0.80, 0.85, 0.90])
ENV_HORIZON = np.array([0.35, 0.42, 0.45])
ENV_FLOOR = np.array([0.10, 0.12, 0.11])
#: (direction, sharpness, radiance) of the two surgical lamps and the wall panel.
ENV_LIGHTS = (
    ((0.3, 1.0, 0.2), 200.0, (40.0, 38.0, 34.0)),
    ((-0.4, 0.9, -0.3), 120.0, (22.0, 24.0, 25.0)),
    ((1.0, 0.15, 0.0), 20.0, (1.5, 2.5, 3.0)),
)

__all__ = ["MIN_ROUGHNESS", "brdf_lut", "brdf_lut_quadrature", "env_radiance", "equirect_dir", "equirect_uv",
           "hammersley", "prefilter", "prefilter_levels"]


def env_radiance(d: np.ndarray) -> np.ndarray:
    """Radiance (..., 3) arriving from unit directions ``d`` (..., 3); +y is up."""
    d = np.asarray(d, dtype=np.float64)
    s = np.clip(d[..., 1], -1.0, 1.0)
    up = np.maximum(s, 0.0)[..., None]
    down = np.maximum(-s, 0.0)[..., None]
    c = ENV_HORIZON + (ENV_CEILING - ENV_HORIZON) * (up * (2.0 - up)) + (ENV_FLOOR - ENV_HORIZON) * (down * (2.0 - down))
    for direction, sharpness, rgb in ENV_LIGHTS:
        axis = np.asarray(direction) / np.linalg.norm(direction)
        c = c + np.asarray(rgb) * np.exp(sharpness * (d @ axis - 1.0))[..., None]
    return c


def equirect_dir(uv: np.ndarray) -> np.ndarray:
    """Unit directions of equirectangular coordinates ``uv`` (..., 2); v = 0 is straight up."""
    uv = np.asarray(uv, dtype=np.float64)
    phi = (uv[..., 0] - 0.5) * 2.0 * np.pi
    theta = uv[..., 1] * np.pi
    st = np.sin(theta)
    return np.stack([st * np.sin(phi), np.cos(theta), -st * np.cos(phi)], axis=-1)


def equirect_uv(d: np.ndarray) -> np.ndarray:
    d = np.asarray(d, dtype=np.float64)
    return np.stack([np.arctan2(d[..., 0], -d[..., 2]) / (2 * np.pi) + 0.5,
                     np.arccos(np.clip(d[..., 1], -1.0, 1.0)) / np.pi], axis=-1)


def hammersley(n: int) -> np.ndarray:
    """(n, 2) points (i / n, radical inverse base 2 of i), as ``hammersley`` in sampling.glsl."""
    i = np.arange(n, dtype=np.uint64)
    r = i.copy()
    r = ((r >> 1) & 0x55555555) | ((r & 0x55555555) << 1)
    r = ((r >> 2) & 0x33333333) | ((r & 0x33333333) << 2)
    r = ((r >> 4) & 0x0F0F0F0F) | ((r & 0x0F0F0F0F) << 4)
    r = ((r >> 8) & 0x00FF00FF) | ((r & 0x00FF00FF) << 8)
    r = ((r >> 16) | (r << 16)) & 0xFFFFFFFF
    return np.stack([i / float(n), r * 2.3283064365386963e-10], axis=-1)


def ggx_sample_tangent(xi: np.ndarray, alpha: float | np.ndarray) -> np.ndarray:
    """Half vectors around +z for GGX (Karis): (..., 3)."""
    alpha = np.asarray(alpha, dtype=np.float64)
    phi = 2.0 * np.pi * xi[..., 0]
    a2 = alpha * alpha
    cos_t = np.sqrt(np.clip((1.0 - xi[..., 1]) / (1.0 + (a2 - 1.0) * xi[..., 1]), 0.0, 1.0))
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=-1)


def onb(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Duff et al. 2017 orthonormal basis (t, b) around unit normals ``n`` (..., 3)."""
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    sgn = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (sgn + z)
    c = x * y * a
    t = np.stack([1.0 + sgn * x * x * a, sgn * c, -sgn * x], axis=-1)
    b = np.stack([c, sgn + y * y * a, -y], axis=-1)
    return t, b


def _lut_terms(nov: np.ndarray, roughness: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Per-sample (A, B) contributions: nov, roughness (...), xi (S, 2) -> (..., S, 2)."""
    alpha = ggx_alpha(roughness)[..., None]
    nov_s = nov[..., None]
    h = ggx_sample_tangent(xi, alpha)  # (..., S, 3)
    v = np.stack([np.sqrt(np.maximum(1.0 - nov * nov, 0.0)), np.zeros_like(nov), nov], axis=-1)[..., None, :]
    voh_raw = np.sum(v * h, axis=-1)
    ldir = 2.0 * voh_raw[..., None] * h - v
    nol = ldir[..., 2]
    noh = np.maximum(h[..., 2], 1e-8)
    voh = np.clip(voh_raw, 0.0, 1.0)
    ok = nol > 0.0
    nol_c = np.where(ok, np.minimum(nol, 1.0), 1.0)
    g_vis = 4.0 * v_smith_ggx_correlated(nov_s, nol_c, alpha) * nol_c * voh / noh
    fc = (1.0 - voh) ** 5
    return np.where(ok[..., None], np.stack([(1.0 - fc) * g_vis, fc * g_vis], axis=-1), 0.0)


def brdf_lut(size: int, samples: int, chunk: int = 4096) -> np.ndarray:
    """The (size, size, 2) LUT the GPU computes: row = roughness, column = N.V (texel centres)."""
    centres = (np.arange(size) + 0.5) / size
    rough, nov = np.meshgrid(centres, centres, indexing="ij")
    xi = hammersley(samples)
    total = np.zeros((size, size, 2))
    for start in range(0, samples, chunk):
        total += _lut_terms(nov, rough, xi[start:start + chunk]).sum(axis=-2)
    return total / samples


def brdf_lut_quadrature(nov: float, roughness: float, n_theta: int = 4096, n_phi: int = 1024) -> np.ndarray:
    """(A, B) by midpoint quadrature of  f * N.L  over the light hemisphere (float64).

    Independent of the importance-sampling estimator: it integrates
    D * V * ((1 - Fc), Fc) * N.L dL directly, with the cosine of the polar angle of L
    as the integration variable. Accurate for roughness >= ~0.2 at the default grid.
    """
    alpha = ggx_alpha(roughness)
    mu = (np.arange(n_theta) + 0.5) / n_theta  # cos(theta_l), uniform in solid angle per phi
    phi = (np.arange(n_phi) + 0.5) / n_phi * np.pi
    mu, phi = np.meshgrid(mu, phi, indexing="ij")
    st = np.sqrt(1.0 - mu * mu)
    ldir = np.stack([st * np.cos(phi), st * np.sin(phi), mu], axis=-1)
    v = np.array([np.sqrt(max(1.0 - nov * nov, 0.0)), 0.0, nov])
    h = ldir + v
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    noh = h[..., 2]
    voh = np.clip(h @ v, 0.0, 1.0)
    d = alpha * alpha / (np.pi * (noh * noh * (alpha * alpha - 1.0) + 1.0) ** 2)
    vis = v_smith_ggx_correlated(nov, mu, alpha)
    fc = (1.0 - voh) ** 5
    f = d * vis * mu
    weight = (1.0 / n_theta) * (np.pi / n_phi) * 2.0
    return np.array([np.sum(f * (1.0 - fc)) * weight, np.sum(f * fc) * weight])


def prefilter(width: int, height: int, roughness: float, samples: int, chunk: int = 64) -> np.ndarray:
    """(height, width, 3) env radiance prefiltered with GGX (N = V = R) at texel centres."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    uu, vv = np.meshgrid(u, v)
    n = equirect_dir(np.stack([uu, vv], axis=-1))
    t, b = onb(n)
    alpha = ggx_alpha(roughness)
    xi = hammersley(samples)
    total = np.zeros((height, width, 3))
    weight = np.zeros((height, width))
    for start in range(0, samples, chunk):
        ht = ggx_sample_tangent(xi[start:start + chunk], alpha)  # (S, 3)
        h = (ht[:, 0, None, None, None] * t + ht[:, 1, None, None, None] * b
             + ht[:, 2, None, None, None] * n)  # (S, H, W, 3)
        noh = np.sum(n * h, axis=-1)
        ldir = 2.0 * noh[..., None] * h - n
        nol = np.sum(n * ldir, axis=-1)
        w = np.where(nol > 0.0, nol, 0.0)
        total += np.sum(env_radiance(ldir) * w[..., None], axis=0)
        weight += w.sum(axis=0)
    out = np.where(weight[..., None] > 0.0, total / np.where(weight > 0.0, weight, 1.0)[..., None], env_radiance(n))
    return np.clip(out, 0.0, HDR_MAX)


def prefilter_levels(width: int, height: int, mips: int, samples: int) -> list[np.ndarray]:
    """Every mip of ``env_map``: mip m is roughness m / (mips - 1) at (width >> m, height >> m)."""
    return [prefilter(max(1, width >> m), max(1, height >> m), m / max(mips - 1, 1), samples) for m in range(mips)]


def brdf_lut_single(nov: float, roughness: float, samples: int, chunk: int = 8192) -> np.ndarray:
    """(A, B) at one (N.V, roughness) with ``samples`` Hammersley points (float64)."""
    xi = hammersley(samples)
    total = np.zeros(2)
    for start in range(0, samples, chunk):
        total += _lut_terms(np.array(float(nov)), np.array(float(roughness)), xi[start:start + chunk]).sum(axis=-2)
    return total / samples
