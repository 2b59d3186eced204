"""NumPy float64 reference of ``tonemap_filmic`` (importable without Vulkan).

Hable's Uncharted 2 filmic curve per channel::

    f(x) = (x (A x + C B) + D E) / (x (A x + B) + D F) - E / F
    A=0.15 B=0.50 C=0.10 D=0.20 E=0.02 F=0.30
    out  = clamp(f(exposure * c) / f(white), 0, 1)        (linear; the sRGB attachment encodes)

Hard inputs (``post_common_ref.sanitize`` and one more rule): a texel with a NaN channel is
black; negative radiance and -Inf -> 0; +Inf -> 1 (white) whatever the exposure; finite
``exposure * c`` is capped at ``1e8`` before the curve (so 1e30 maps to white, never Inf/Inf).
Alpha is 1. Defaults: exposure 2.0 (Hable's exposure bias), white 11.2.

Tolerance (GPU vs reference): one 8-bit sRGB code, compared on the sRGB-encoded bytes.
"""

from __future__ import annotations

import numpy as np

from .post_common_ref import sanitize

A, B, C, D, E, F = 0.15, 0.50, 0.10, 0.20, 0.02, 0.30
X_CAP = 1e8
TOLERANCE_SRGB_CODES = 1


def hable(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F


def reference(hdr: np.ndarray, exposure: float = 2.0, white: float = 11.2) -> np.ndarray:
    """(h, w, 4) linear output in [0, 1] from (h, w, >=3) radiance."""
    rgb = np.asarray(hdr, dtype=np.float64)[..., :3]
    pos_inf = np.isposinf(rgb) & ~np.isnan(rgb).any(axis=-1, keepdims=True)
    c = sanitize(rgb, np.inf)  # NaN texel -> 0, negatives -> 0 (the cap below bounds +Inf)
    c = np.where(np.isinf(c), 0.0, c)
    x = np.minimum(c * exposure, X_CAP)
    mapped = np.clip(hable(x) / hable(np.float64(min(white, X_CAP))), 0.0, 1.0)
    mapped = np.where(pos_inf, 1.0, mapped)
    return np.concatenate([mapped, np.ones(mapped.shape[:-1] + (1,))], axis=-1)


def srgb_codes(linear: np.ndarray) -> np.ndarray:
    """Linear [0, 1] values -> 8-bit sRGB codes (what an r8g8b8a8_srgb store writes), as int."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    enc = np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(enc * 255.0).astype(int)
