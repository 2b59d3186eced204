"""Shared NumPy float64 rules of the post-processing passes: luma, half-float limits, and the
non-finite sanitizing rule (importable without Vulkan).

Sanitizing rule (``sanitize``; bloom's bright pass and the tonemap both apply it per texel):
a texel with a NaN in any colour channel becomes black (0, 0, 0); otherwise each channel is
clamped to ``[0, hi]`` (negative radiance and -Inf -> 0, +Inf and values above ``hi`` -> ``hi``).
"""

from __future__ import annotations

import numpy as np

HALF_MAX = 65504.0
LUMA = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709


def luma(rgb: np.ndarray) -> np.ndarray:
    return np.asarray(rgb, dtype=np.float64)[..., :3] @ LUMA


def sanitize(rgb: np.ndarray, hi: float) -> np.ndarray:
    """The rule above on (..., 3) colours (float64 result)."""
    rgb = np.asarray(rgb, dtype=np.float64)[..., :3]
    bad = np.isnan(rgb).any(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore"):
        return np.where(bad, 0.0, np.clip(np.nan_to_num(rgb, nan=0.0, posinf=hi, neginf=0.0), 0.0, hi))


def to_half(x: np.ndarray) -> np.ndarray:
    """Round float64 values to float16 storage the way an r16g16b16a16_sfloat store does (RNE)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.asarray(x, dtype=np.float64).astype(np.float16).astype(np.float64)
