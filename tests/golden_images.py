"""Golden-image comparisons for tests: ``assert_image_close(name, image, tolerance)``.

Goldens are 8-bit RGBA PNGs in ``tests/golden/images/<name>.png``. On a mismatch the
actual image and a diff image are written to ``tests/golden/images/failures/`` (ignored by
git) and the assertion message gives the max and mean absolute error (8-bit levels) and the
share of pixels over the tolerance. ``RGRAPH_UPDATE_GOLDEN=1`` (re)writes the golden instead.

Images are (h, w) or (h, w, 1..4) arrays: ``uint8`` is taken as stored bytes; floats are
values in [0, 1], by default *linear* values as ``RunResult.outputs`` decodes an ``*_srgb``
image, so they are sRGB-encoded before quantizing (``encoding="linear"`` stores them as they
are, e.g. for a ``*_unorm`` image). PNG reading and writing use zlib and struct only.
"""

from __future__ import annotations

import os
import struct
import zlib
from pathlib import Path

import numpy as np

from rgraph.png import write_png

GOLDEN_DIR = Path(__file__).parent / "golden" / "images"
UPDATE_ENV = "RGRAPH_UPDATE_GOLDEN"

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}  # PNG colour type -> samples per pixel


def read_png(path: Path) -> np.ndarray:
    """An (h, w, 4) uint8 array from an 8-bit, non-interlaced PNG (grey, grey+alpha, RGB,
    RGBA or palette)."""
    data = Path(path).read_bytes()
    if not data.startswith(_PNG_SIGNATURE):
        raise ValueError(f"{path}: not a PNG file")
    pos, header, palette, alpha_table, idat = 8, None, None, None, []
    while pos + 8 <= len(data):
        length, tag = struct.unpack(">I4s", data[pos:pos + 8])
        payload = data[pos + 8:pos + 8 + length]
        if zlib.crc32(tag + payload) != struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])[0]:
            raise ValueError(f"{path}: bad CRC in chunk {tag.decode(errors='replace')}")
        pos += 12 + length
        if tag == b"IHDR":
            header = struct.unpack(">IIBBBBB", payload)
        elif tag == b"PLTE":
            palette = np.frombuffer(payload, dtype=np.uint8).reshape(-1, 3)
        elif tag == b"tRNS":
            alpha_table = np.frombuffer(payload, dtype=np.uint8)
        elif tag == b"IDAT":
            idat.append(payload)
        elif tag == b"IEND":
            break
    if header is None:
        raise ValueError(f"{path}: no IHDR chunk")
    width, height, depth, colour, _, _, interlace = header
    if depth != 8 or interlace != 0 or colour not in _CHANNELS:
        raise ValueError(f"{path}: only 8-bit non-interlaced PNGs are supported (depth {depth}, colour type "
                         f"{colour}, interlace {interlace})")
    bpp = _CHANNELS[colour]
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8)
    stride = width * bpp
    if raw.size != height * (stride + 1):
        raise ValueError(f"{path}: image data holds {raw.size} bytes, expected {height * (stride + 1)}")
    rows = raw.reshape(height, stride + 1)
    out = np.zeros((height, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int32)
    for y in range(height):
        kind, line = rows[y, 0], rows[y, 1:].astype(np.int32)
        if kind == 0:
            cur = line
        elif kind == 2:
            cur = (line + prev) & 0xFF
        elif kind == 1:
            cur = np.cumsum(line.reshape(width, bpp), axis=0).reshape(stride) & 0xFF
        elif kind in (3, 4):
            cur = np.zeros(stride, dtype=np.int32)
            for x in range(stride):  # Average and Paeth depend on the left neighbour: sequential
                left = cur[x - bpp] if x >= bpp else 0
                if kind == 3:
                    pred = (left + prev[x]) >> 1
                else:
                    up_left = prev[x - bpp] if x >= bpp else 0
                    p = left + prev[x] - up_left
                    pa, pb, pc = abs(p - left), abs(p - prev[x]), abs(p - up_left)
                    pred = left if pa <= pb and pa <= pc else prev[x] if pb <= pc else up_left
                cur[x] = (line[x] + pred) & 0xFF
        else:
            raise ValueError(f"{path}: bad filter type {kind} in row {y}")
        out[y] = cur
        prev = cur
    pixels = out.reshape(height, width, bpp)
    if colour == 3:
        if palette is None:
            raise ValueError(f"{path}: palette image without PLTE")
        alpha = np.full(len(palette), 255, dtype=np.uint8)
        if alpha_table is not None:
            alpha[:len(alpha_table)] = alpha_table
        return np.concatenate([palette[pixels[..., 0]], alpha[pixels[..., 0]][..., None]], axis=-1)
    return to_rgba8(pixels)


def _linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def to_rgba8(image: np.ndarray, encoding: str = "srgb") -> np.ndarray:
    """An (h, w, 4) uint8 array from uint8 bytes or float values (see the module docstring).
    Grey becomes grey RGB, grey+alpha keeps its alpha, missing alpha is opaque."""
    if encoding not in ("srgb", "linear"):
        raise ValueError(f"encoding must be 'srgb' or 'linear', got {encoding!r}")
    img = np.asarray(image)
    if img.ndim == 2:
        img = img[..., None]
    if img.ndim != 3 or not 1 <= img.shape[-1] <= 4:
        raise ValueError(f"expected an (h, w) or (h, w, 1..4) image, got shape {img.shape}")
    if img.dtype != np.uint8:
        if not np.issubdtype(img.dtype, np.floating):
            raise ValueError(f"images are uint8 bytes or floats in [0, 1], got dtype {img.dtype}")
        values = np.nan_to_num(img.astype(np.float64), nan=0.0, posinf=1.0, neginf=0.0)
        if encoding == "srgb":
            values[..., :3] = _linear_to_srgb(values[..., :3])
        img = np.round(np.clip(values, 0.0, 1.0) * 255.0).astype(np.uint8)
    h, w, c = img.shape
    out = np.full((h, w, 4), 255, dtype=np.uint8)
    if c in (1, 2):
        out[..., :3] = img[..., :1]
        if c == 2:
            out[..., 3] = img[..., 1]
    else:
        out[..., :c] = img
    return out


def diff_image(actual: np.ndarray, golden: np.ndarray, tolerance: int) -> np.ndarray:
    """Per-pixel largest channel error as grey (amplified x8), pixels over tolerance in red."""
    err = np.abs(actual.astype(np.int32) - golden.astype(np.int32)).max(axis=-1)
    grey = np.clip(err * 8, 0, 255).astype(np.uint8)
    out = np.stack([grey, grey, grey, np.full_like(grey, 255)], axis=-1)
    out[err > tolerance] = (255, 0, 0, 255)
    return out


def assert_image_close(name: str, image: np.ndarray, tolerance: int = 1, *, encoding: str = "srgb",
                       max_fraction_over: float = 0.0, golden_dir: Path | None = None) -> None:
    """Compare ``image`` with ``<golden_dir>/<name>.png``: every channel within ``tolerance``
    8-bit levels, except at most ``max_fraction_over`` of the pixels. See the module docstring."""
    directory = Path(golden_dir) if golden_dir is not None else GOLDEN_DIR
    golden_path = directory / f"{name}.png"
    actual = to_rgba8(image, encoding)
    if os.environ.get(UPDATE_ENV) == "1":
        directory.mkdir(parents=True, exist_ok=True)
        write_png(golden_path, actual)
        return
    failures = directory / "failures"
    if not golden_path.exists():
        failures.mkdir(parents=True, exist_ok=True)
        write_png(failures / f"{name}.actual.png", actual)
        raise AssertionError(f"golden image {golden_path} does not exist; actual image written to "
                             f"{failures / (name + '.actual.png')}; run with {UPDATE_ENV}=1 to create it")
    golden = read_png(golden_path)
    if golden.shape != actual.shape:
        failures.mkdir(parents=True, exist_ok=True)
        write_png(failures / f"{name}.actual.png", actual)
        raise AssertionError(f"image {name!r}: size {actual.shape[1]}x{actual.shape[0]} differs from the golden's "
                             f"{golden.shape[1]}x{golden.shape[0]} ({golden_path}); actual written to "
                             f"{failures / (name + '.actual.png')}")
    err = np.abs(actual.astype(np.int32) - golden.astype(np.int32))
    over = err.max(axis=-1) > tolerance
    fraction = float(over.mean())
    if fraction > max_fraction_over:
        failures.mkdir(parents=True, exist_ok=True)
        actual_path, diff_path = failures / f"{name}.actual.png", failures / f"{name}.diff.png"
        write_png(actual_path, actual)
        write_png(diff_path, diff_image(actual, golden, tolerance))
        raise AssertionError(
            f"image {name!r} differs from {golden_path}: max abs error {int(err.max())}, mean abs error "
            f"{float(err.mean()):.3f} (8-bit levels), {100.0 * fraction:.2f}% of pixels over tolerance {tolerance} "
            f"(allowed {100.0 * max_fraction_over:.2f}%); wrote {actual_path} and {diff_path}; "
            f"rerun with {UPDATE_ENV}=1 if the change is intended")
