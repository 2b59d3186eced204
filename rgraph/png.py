"""PNG output: an output image as RGBA8 (rendered colour, or the probe's value view) and a
minimal PNG writer."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from rgraph.probe.values import codec


def image_to_rgba8(resource: dict, data: bytes, width: int, height: int) -> np.ndarray:
    """An (h, w, 4) uint8 view of probe values (scaled to 0..255 by the format's value range)."""
    c = codec(resource["format"])
    if c is None:
        return np.zeros((height, width, 4), dtype=np.uint8)
    values = c.decode(data).reshape(height, width, c.components).astype(np.float64)
    scaled = np.clip(values * (255.0 / max(c.modulus - 1, 1)), 0, 255).astype(np.uint8)
    rgba = np.zeros((height, width, 4), dtype=np.uint8)
    rgba[..., 3] = 255
    for ch in range(min(c.components, 4)):
        rgba[..., ch] = scaled[..., ch]
    if c.components == 1:
        rgba[..., 1] = rgba[..., 2] = rgba[..., 0]
    return rgba


def write_png(path: Path, rgba: np.ndarray) -> None:
    """A minimal RGBA8 PNG writer (zlib + struct)."""
    height, width = rgba.shape[:2]
    raw = b"".join(b"\0" + rgba[y].tobytes() for y in range(height))

    def chunk(tag: bytes, payload: bytes) -> bytes:
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload))

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")
    Path(path).write_bytes(png)


#: Float formats whose channels are all 16- or 32-bit IEEE floats: (channels, numpy dtype).
_FLOAT_LAYOUTS = {"".join(f"{c}{bits}" for c in "rgba"[:n]) + "_sfloat": (n, dtype)
                  for bits, dtype in (("16", np.float16), ("32", np.float32)) for n in (1, 2, 3, 4)}


def float_rgba8(raw: bytes, fmt: str, w: int, h: int) -> np.ndarray | None:
    """RGBA8 of a rendered float image (linear values clamped to [0, 1] as stored, like
    ``rgraph sweep``'s images of float outputs; NaN as 0; one channel as grey), or None
    when ``fmt`` is not an all-16-bit or all-32-bit float format."""
    layout = _FLOAT_LAYOUTS.get(fmt.lower())
    if layout is None:
        return None
    channels, dtype = layout
    values = np.frombuffer(raw, dtype=dtype, count=w * h * channels).reshape(h, w, channels).astype(np.float64)
    values = np.nan_to_num(np.clip(values, 0.0, 1.0), nan=0.0)
    rgba = np.full((h, w, 4), 255, dtype=np.uint8)
    rgb = values[..., [0, 0, 0]] if channels == 1 else values[..., [0, 1, min(2, channels - 1)]]
    if channels == 2:
        rgb[..., 2] = 0.0
    rgba[..., :3] = np.rint(rgb * 255.0).astype(np.uint8)
    return rgba


def output_rgba(res: dict, raw: bytes, w: int, h: int, implemented: bool) -> np.ndarray:
    """RGBA8 for a PNG: the stored bytes of an 8-bit colour image rendered by real passes (a
    float one clamped: :func:`float_rgba8`), else the probe's value visualisation."""
    channel_order = {"r8g8b8a8": [0, 1, 2, 3], "b8g8r8a8": [2, 1, 0, 3]}
    head, _, kind = res["format"].lower().rpartition("_")
    if implemented and head in channel_order and kind in ("srgb", "unorm"):
        rgba = np.frombuffer(raw, dtype=np.uint8, count=w * h * 4).reshape(h, w, 4)[..., channel_order[head]].copy()
        rgba[..., 3] = 255
        return rgba
    rendered = float_rgba8(raw, res["format"], w, h) if implemented else None
    return rendered if rendered is not None else image_to_rgba8(res, raw, w, h)


def first_output_image(plan: dict) -> dict | None:
    """The plan's first output image (what ``rgraph run --out`` writes), or None."""
    return next((r for r in plan["resources"] if r["lifetime"] == "output" and r["kind"] == "image"), None)


def write_output_png(plan: dict, data: dict[tuple, bytes], path: Path) -> None:
    """Write the plan's first output image from read-back bytes (``read_back``) as a PNG: mip 0,
    its layers side by side, left to right (``views=2``: the left eye, then the right)."""
    from rgraph.probe.semantics import mip_extent

    res = first_output_image(plan)
    if res is None:
        raise ValueError("the plan has no output image")
    w, h = mip_extent(res, 0)
    implemented = any(p.get("impl") for p in plan["passes"])
    layers = [k for k in range(int(res.get("layers", 1))) if (res["name"], 0, k) in data]
    tiles = [output_rgba(res, data[(res["name"], 0, k)], w, h, implemented) for k in layers or [0]]
    write_png(Path(path), tiles[0] if len(tiles) == 1 else np.concatenate(tiles, axis=1))
