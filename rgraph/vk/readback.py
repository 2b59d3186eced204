"""Reading resources back after the frames, comparing with the simulation, writing PNG."""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rgraph.probe.values import HEADER_WORDS, codec, has_header, header_words


@dataclass
class Mismatch:
    resource: str
    sub: tuple[int, int] | None
    expected: int | None
    got: str

    def __str__(self) -> str:
        where = f" mip {self.sub[0]} layer {self.sub[1]}" if self.sub else ""
        return f"{self.resource}{where}: expected {self.expected}, got {self.got}"


def _summary(values: np.ndarray) -> str:
    uniq, counts = np.unique(values, return_counts=True)
    order = np.argsort(-counts)[:4]
    parts = [f"{int(uniq[i])} x{int(counts[i])}" for i in order]
    return ", ".join(parts) + (" ..." if len(uniq) > 4 else "")


def compare_image(resource: dict, sub: tuple[int, int], data: bytes, expected: int | None) -> Mismatch | None:
    c = codec(resource["format"])
    if c is None or expected is None:
        return None
    values = c.decode(data)
    if values.size and np.all(values == expected):
        return None
    return Mismatch(resource["name"], sub, expected, _summary(values))


def compare_buffer(resource: dict, data: bytes, expected: int | None, plan_size: tuple[int, int]) -> list[Mismatch]:
    if expected is None:
        return []
    words = np.frombuffer(data[: len(data) // 4 * 4], dtype=np.uint32).astype(np.int64)
    out = []
    if has_header(resource):
        header = np.array(header_words(plan_size), dtype=np.int64)
        if not np.array_equal(words[:HEADER_WORDS], header):
            out.append(Mismatch(resource["name"], None, None, f"indirect header {words[:HEADER_WORDS].tolist()}"))
        words = words[HEADER_WORDS:]
    if not np.all(words == expected):
        out.append(Mismatch(resource["name"], None, expected, _summary(words)))
    return out


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
