"""NumPy float64 reference of the bloom chain (importable without Vulkan).

``bright``  (``bloom_bright``): each output texel of the reduced image covers an ``f x f``
block of ``hdr`` texels (``f = hdr extent // bloom extent`` per axis; 4 at quarter size).
Every source texel is sanitized (``post_common_ref.sanitize`` with ``hi = bloom.clamp``:
NaN texel -> black, negative/-Inf -> 0, +Inf -> ``bloom.clamp``), then the block is reduced
with the Karis average ``sum(w c) / sum(w)``, ``w = 1 / (1 + luma(c))``, so that one firefly
(even +Inf) adds at most about ``1/(f*f)`` to its block instead of exploding. The average
``a`` is thresholded with a soft knee (``k = threshold * knee``, ``br = max(a.rgb)``)::

    soft = clamp(br - threshold + k, 0, 2k)^2 / (4k + 1e-5)   (0 when k == 0)
    out  = a * max(soft, br - threshold) / max(br, 1e-5)

``blur``    (``bloom_blur``): separable Gaussian along ``direction`` with taps ``-r..r``,
weights ``exp(-i^2 / (2 sigma^2))`` normalized to sum 1, clamp-to-edge, ``r`` and ``sigma``
in texels of the reduced image. The graph params are in HDR (full-resolution) pixels so
that every ``bloom.scale`` approximates the same filter: ``bloom.radius`` (default 16) is
the truncation radius and ``bloom.sigma`` (default radius / 2) the standard deviation; at
reduction factor ``f`` (``hdr extent // bloom extent`` along the blur's axis) the pass uses
``r = round(radius / f)`` taps each side (half up) and ``sigma / f`` (``working_blur``).
At the default quarter size that is the former 4 taps with sigma 2.

Reference setting of ``rgraph sweep``: ``bloom.scale=1``. There the bright pass averages
one texel (the Karis average of a single texel is the texel: only the sanitizing and the
soft threshold act), and the separable Gaussian IS the full-resolution 2D Gaussian
convolution (a 2D Gaussian factors exactly into two 1D ones), so the chain computes the
truth that quarter resolution approximates, up to the truncation at ``bloom.radius``.
``combine`` (``bloom_combine``): ``hdr + intensity * bilinear(bloom)`` where full-resolution
pixel ``p`` samples the bloom image at texel coordinate ``(p + 0.5) / f - 0.5`` (clamp to edge).

Every stage stores float16, which the reference mirrors (``to_half``). Tolerance (GPU vs
reference, each stage and the whole chain): ``|gpu - ref| <= 4e-3 * |ref| + 2e-4``.
"""

from __future__ import annotations

import math

import numpy as np

from .post_common_ref import HALF_MAX, luma, sanitize, to_half

RTOL = 4e-3
ATOL = 2e-4
MAX_RADIUS = 28  # push-constant room for weights 0..28


def gaussian_weights(radius: int, sigma: float | None = None) -> np.ndarray:
    """Normalized one-sided weights ``w[0..radius]`` (w[i] applies to taps +i and -i)."""
    if not 0 <= radius <= MAX_RADIUS:
        raise ValueError(f"bloom.radius must be in [0, {MAX_RADIUS}], got {radius}")
    sigma = default_sigma(radius) if sigma is None else float(sigma)
    if not sigma > 0:
        raise ValueError(f"bloom.sigma must be > 0, got {sigma}")
    w = np.array([math.exp(-(i * i) / (2.0 * sigma * sigma)) for i in range(radius + 1)])
    return w / (w[0] + 2.0 * w[1:].sum())


def default_sigma(radius: float) -> float:
    return max(radius, 1) / 2.0


def working_blur(radius: float, sigma: float | None, factor: int) -> tuple[int, float]:
    """(taps each side, sigma) in reduced-image texels for a blur given in HDR pixels."""
    if factor < 1:
        raise ValueError(f"bloom reduction factor must be >= 1, got {factor}")
    if not radius >= 0:
        raise ValueError(f"bloom.radius must be >= 0, got {radius}")
    sigma = default_sigma(radius) if sigma is None else float(sigma)
    return int(math.floor(radius / factor + 0.5)), sigma / factor


def bright(hdr: np.ndarray, out_size: tuple[int, int], threshold: float = 1.0, knee: float = 0.5,
           clamp: float = HALF_MAX) -> np.ndarray:
    """(H, W, 4) hdr -> (out_h, out_w, 4) float16-rounded bright-pass image (``out_size`` = (w, h))."""
    ow, oh = out_size
    h, w = hdr.shape[:2]
    fx, fy = max(1, w // ow), max(1, h // oh)
    c = sanitize(hdr, clamp)
    ys = np.minimum(np.arange(oh)[:, None] * fy + np.arange(fy)[None, :], h - 1)  # (oh, fy)
    xs = np.minimum(np.arange(ow)[:, None] * fx + np.arange(fx)[None, :], w - 1)  # (ow, fx)
    block = c[ys[:, None, :, None], xs[None, :, None, :]]  # (oh, ow, fy, fx, 3)
    wgt = 1.0 / (1.0 + luma(block))
    a = (block * wgt[..., None]).sum(axis=(2, 3)) / wgt.sum(axis=(2, 3))[..., None]
    br = a.max(axis=-1)
    k = threshold * knee
    soft = np.clip(br - threshold + k, 0.0, 2.0 * k)
    soft = soft * soft / (4.0 * k + 1e-5) if k > 0 else np.zeros_like(br)
    contrib = np.maximum(soft, br - threshold) / np.maximum(br, 1e-5)
    rgb = a * contrib[..., None]
    return to_half(np.concatenate([rgb, np.ones((oh, ow, 1))], axis=-1))


def blur(img: np.ndarray, direction: str, radius: int = 4, sigma: float | None = None) -> np.ndarray:
    """One separable Gaussian pass (``direction``: ``h`` or ``v``); float16-rounded."""
    weights = gaussian_weights(radius, sigma)
    src = np.asarray(img, dtype=np.float64)
    axis = 1 if direction == "h" else 0
    n = src.shape[axis]
    out = np.zeros_like(src)
    for i in range(-radius, radius + 1):
        idx = np.clip(np.arange(n) + i, 0, n - 1)
        out += weights[abs(i)] * np.take(src, idx, axis=axis)
    return to_half(out)


def upsample_bilinear(img: np.ndarray, out_size: tuple[int, int], factor: tuple[int, int]) -> np.ndarray:
    """Bilinear, clamp-to-edge: output pixel p samples texel coordinate ``(p + 0.5) / f - 0.5``."""
    ow, oh = out_size
    h, w = img.shape[:2]

    def axis(n_out: int, n_in: int, f: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s = (np.arange(n_out) + 0.5) / f - 0.5
        i0 = np.floor(s)
        t = s - i0
        i0 = i0.astype(int)
        return np.clip(i0, 0, n_in - 1), np.clip(i0 + 1, 0, n_in - 1), t

    y0, y1, ty = axis(oh, h, factor[1])
    x0, x1, tx = axis(ow, w, factor[0])
    img = np.asarray(img, dtype=np.float64)
    top = img[y0][:, x0] * (1 - tx)[None, :, None] + img[y0][:, x1] * tx[None, :, None]
    bot = img[y1][:, x0] * (1 - tx)[None, :, None] + img[y1][:, x1] * tx[None, :, None]
    return top * (1 - ty)[:, None, None] + bot * ty[:, None, None]


def combine(hdr: np.ndarray, bloom: np.ndarray, intensity: float) -> np.ndarray:
    """``hdr`` (H, W, 4) plus ``intensity`` times the upsampled bloom (rgb only; alpha kept)."""
    h, w = hdr.shape[:2]
    bh, bw = bloom.shape[:2]
    up = upsample_bilinear(bloom, (w, h), (max(1, w // bw), max(1, h // bh)))
    out = np.asarray(hdr, dtype=np.float64).copy()
    with np.errstate(invalid="ignore", over="ignore"):
        out[..., :3] = out[..., :3] + intensity * up[..., :3]
    return to_half(out)


def chain(hdr: np.ndarray, bloom_size: tuple[int, int], *, threshold: float = 1.0, knee: float = 0.5,
          clamp: float = HALF_MAX, radius: float = 16, sigma: float | None = None,
          intensity: float = 0.05) -> dict[str, np.ndarray]:
    """The whole chain as the surgery graph runs it: bright -> blur h -> blur v -> combine.
    ``radius`` and ``sigma`` in HDR pixels (see ``working_blur``)."""
    h, w = hdr.shape[:2]
    fx, fy = max(1, w // bloom_size[0]), max(1, h // bloom_size[1])
    a = bright(hdr, bloom_size, threshold, knee, clamp)
    b = blur(a, "h", *working_blur(radius, sigma, fx))
    a2 = blur(b, "v", *working_blur(radius, sigma, fy))
    return {"bright": a, "blur_h": b, "bloom": a2, "hdr": combine(hdr, a2, intensity)}
