"""Texel bytes <-> NumPy arrays of the values shaders see (floats; sRGB decoded to linear).

Covers the uncompressed colour and depth formats passes use: ``*_unorm``/``*_snorm``/
``*_srgb`` with 8- or 16-bit channels, ``*_sfloat`` with 16- or 32-bit channels,
``*_uint``/``*_sint`` (as integers), ``d32_sfloat`` and ``d16_unorm``.
"""

from __future__ import annotations

import re

import numpy as np

_CHANNELS = re.compile(r"([rgbad])(\d+)")


def _layout(format_name: str) -> tuple[int, int, str]:
    """(channels, bits per channel, numeric kind) of a plain format, or ValueError."""
    head, _, kind = format_name.lower().rpartition("_")
    parts = _CHANNELS.findall(head)
    if not parts or len({bits for _, bits in parts}) != 1 or "".join(c for c, _ in parts) not in (
            "r", "rg", "rgb", "rgba", "bgra", "d"):
        raise ValueError(f"texel codec: unsupported format {format_name!r}")
    return len(parts), int(parts[0][1]), kind


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def _dtype(bits: int, kind: str) -> np.dtype:
    if kind == "sfloat":
        return np.dtype({16: "<f2", 32: "<f4", 64: "<f8"}[bits])
    signed = kind in ("snorm", "sint")
    return np.dtype(f"<{'i' if signed else 'u'}{bits // 8}")


def decode(format_name: str, data: bytes, width: int, height: int) -> np.ndarray:
    """An (height, width, channels) array: float32 for float/normalized formats, ints otherwise."""
    channels, bits, kind = _layout(format_name)
    raw = np.frombuffer(data, dtype=_dtype(bits, kind), count=width * height * channels).reshape(height, width, channels)
    if format_name.lower().startswith("b") and channels >= 3:
        raw = raw[..., [2, 1, 0, 3][:channels]]
    if kind in ("uint", "sint"):
        return raw.copy()
    if kind == "sfloat":
        return raw.astype(np.float32)
    top = float(2 ** (bits - (1 if kind == "snorm" else 0)) - 1)
    values = raw.astype(np.float64) / top
    if kind == "snorm":
        values = np.maximum(values, -1.0)
    if kind == "srgb":
        values[..., :3] = srgb_to_linear(values[..., :3])
    return values.astype(np.float32)


def encode(format_name: str, values: np.ndarray) -> bytes:
    """Texel bytes for an (height, width, channels) array of shader-visible values."""
    channels, bits, kind = _layout(format_name)
    values = np.asarray(values)
    if values.ndim == 2:
        values = values[..., None]
    if values.shape[-1] != channels:
        raise ValueError(f"{format_name}: {values.shape[-1]} channels given, {channels} expected")
    if format_name.lower().startswith("b") and channels >= 3:
        values = values[..., [2, 1, 0, 3][:channels]]
    dtype = _dtype(bits, kind)
    if kind in ("uint", "sint", "sfloat"):
        return np.ascontiguousarray(values.astype(dtype)).tobytes()
    v = values.astype(np.float64)
    if kind == "srgb":
        v = v.copy()
        v[..., :3] = linear_to_srgb(v[..., :3])
    lo = -1.0 if kind == "snorm" else 0.0
    top = float(2 ** (bits - (1 if kind == "snorm" else 0)) - 1)
    return np.ascontiguousarray(np.round(np.clip(v, lo, 1.0) * top).astype(dtype)).tobytes()
