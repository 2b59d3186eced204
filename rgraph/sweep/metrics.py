"""Image error metrics in NumPy: PSNR, SSIM (Wang et al. 2004) and HDR metrics.

LDR metrics take display-encoded images (sRGB-encoded values in [0, 1], ``H x W x 3``);
HDR metrics take linear radiance (``H x W x 3``, non-negative).
"""

from __future__ import annotations

import math

import numpy as np

# Wang, Bovik, Sheikh, Simoncelli 2004, "Image quality assessment: from error visibility
# to structural similarity": 11x11 circular-symmetric Gaussian window, sigma 1.5.
SSIM_WINDOW = 11
SSIM_SIGMA = 1.5
SSIM_K1 = 0.01
SSIM_K2 = 0.03
REL_MSE_EPSILON = 0.01  # relMSE denominator guard (Rousselle et al. 2011)

REC709_LUMA = np.array([0.2126, 0.7152, 0.0722])


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Rec. 709 weighted sum of the first three channels (one channel passes through)."""
    rgb = np.asarray(rgb, dtype=np.float64)
    if rgb.ndim == 2:
        return rgb
    if rgb.shape[-1] == 1:
        return rgb[..., 0]
    return rgb[..., :3] @ REC709_LUMA


def _same_shape(a: np.ndarray, b: np.ndarray) -> None:
    if a.shape != b.shape:
        raise ValueError(f"images differ in shape: {a.shape} vs {b.shape}")


def mse(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    _same_shape(a, b)
    return float(np.mean((a - b) ** 2))


def psnr(reference: np.ndarray, test: np.ndarray, peak: float = 1.0) -> float:
    """Peak signal-to-noise ratio in dB; ``inf`` for identical images."""
    err = mse(reference, test)
    if err == 0.0:
        return math.inf
    return 10.0 * math.log10(peak * peak / err)


def gaussian_window(size: int = SSIM_WINDOW, sigma: float = SSIM_SIGMA) -> np.ndarray:
    """Normalized 1-D Gaussian taps; the 2-D window is their outer product."""
    x = np.arange(size, dtype=np.float64) - (size - 1) / 2.0
    taps = np.exp(-(x * x) / (2.0 * sigma * sigma))
    return taps / taps.sum()


def _filter_valid(image: np.ndarray, taps: np.ndarray) -> np.ndarray:
    """Separable correlation with ``taps`` on both axes, 'valid' region only (as Wang's
    reference code's ``filter2(w, img, 'valid')``)."""
    n = len(taps)
    h, w = image.shape
    rows = sum(taps[i] * image[i:h - n + 1 + i, :] for i in range(n))
    return sum(taps[i] * rows[:, i:w - n + 1 + i] for i in range(n))


def ssim_map(reference: np.ndarray, test: np.ndarray, data_range: float = 1.0,
             window: int = SSIM_WINDOW, sigma: float = SSIM_SIGMA) -> np.ndarray:
    """Per-window SSIM of two single-channel images (valid region: (H-w+1) x (W-w+1)).

    Images smaller than the window use a window of their smaller side (made odd)."""
    x, y = np.asarray(reference, np.float64), np.asarray(test, np.float64)
    _same_shape(x, y)
    if x.ndim != 2:
        raise ValueError(f"ssim_map expects single-channel images, got shape {x.shape}")
    size = min(window, *x.shape)
    size -= 1 - size % 2
    taps = gaussian_window(size, sigma)
    c1 = (SSIM_K1 * data_range) ** 2
    c2 = (SSIM_K2 * data_range) ** 2
    mu_x, mu_y = _filter_valid(x, taps), _filter_valid(y, taps)
    sxx = _filter_valid(x * x, taps) - mu_x * mu_x
    syy = _filter_valid(y * y, taps) - mu_y * mu_y
    sxy = _filter_valid(x * y, taps) - mu_x * mu_y
    num = (2.0 * mu_x * mu_y + c1) * (2.0 * sxy + c2)
    den = (mu_x * mu_x + mu_y * mu_y + c1) * (sxx + syy + c2)
    return num / den


def ssim(reference: np.ndarray, test: np.ndarray, data_range: float = 1.0) -> float:
    """Mean SSIM on luminance (Rec. 709 luma of the given values, Wang et al. constants)."""
    return float(np.mean(ssim_map(luminance(reference), luminance(test), data_range)))


def rel_mse(reference: np.ndarray, test: np.ndarray, epsilon: float = REL_MSE_EPSILON) -> float:
    """Relative MSE ``mean((t - r)^2 / (r^2 + eps))``: HDR error that weighs dark and
    bright regions alike."""
    r, t = np.asarray(reference, np.float64), np.asarray(test, np.float64)
    _same_shape(r, t)
    return float(np.mean((t - r) ** 2 / (r * r + epsilon)))


def log_psnr(reference: np.ndarray, test: np.ndarray) -> float:
    """PSNR of ``log2(1 + x)`` (negative values clamped to 0), peak = the reference's
    largest log value (at least 1): an HDR PSNR that does not let highlights dominate."""
    r = np.log2(1.0 + np.maximum(np.asarray(reference, np.float64), 0.0))
    t = np.log2(1.0 + np.maximum(np.asarray(test, np.float64), 0.0))
    peak = max(float(r.max(initial=0.0)), 1.0)
    return psnr(r, t, peak=peak)


def abs_difference(reference: np.ndarray, test: np.ndarray) -> np.ndarray:
    """Per-pixel mean absolute difference over channels (``H x W``)."""
    r, t = np.asarray(reference, np.float64), np.asarray(test, np.float64)
    _same_shape(r, t)
    diff = np.abs(t - r)
    return diff.mean(axis=-1) if diff.ndim == 3 else diff
