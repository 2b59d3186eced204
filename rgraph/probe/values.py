"""How the probe stores small integers in each format, exactly, and how it derives them.

Every image subresource (mip, layer) the probe writes holds one value ``v`` in every texel
and every component; every buffer holds ``v`` in every 32-bit word of its body. Buffers
used as ``indirect`` start with a 64-byte header of valid draw/dispatch arguments.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from rgraph import formats

HEADER_WORDS = 16  # indirect-capable buffers: words [0:4] draw, [4:9] indexed draw, [12:15] dispatch
INDIRECT_MIN_BYTES = 4 * (HEADER_WORDS + 1)  # the header plus one value word: what the probe needs
BUFFER_MODULUS = 1 << 30
UINT32 = 0xFFFFFFFF


@dataclass(frozen=True)
class Codec:
    """One format's exact integer encoding."""

    kind: str  # unorm | snorm | srgb | sfloat | uint | sint | depth_unorm | depth_sfloat
    bits: int  # bits per component
    components: int
    modulus: int  # values live in [0, modulus)

    @property
    def glsl_prefix(self) -> str:
        return {"uint": "u", "sint": "i"}.get(self.kind, "")

    @property
    def scale(self) -> float:
        """Float written per unit value (unorm/snorm/depth/float kinds)."""
        if self.kind in ("unorm", "srgb", "depth_unorm"):
            return 1.0 / ((1 << self.bits) - 1)
        if self.kind == "snorm":
            return 1.0 / ((1 << (self.bits - 1)) - 1)
        if self.kind == "depth_sfloat":
            return 1.0 / 65536.0
        return 1.0

    def encode(self, value: int) -> bytes:
        """One texel's bytes holding ``value`` in every component."""
        n = self.components
        if self.kind in ("unorm", "srgb", "uint", "depth_unorm"):
            dtype = {8: np.uint8, 16: np.uint16, 32: np.uint32}[self.bits]
            return np.full(n, value, dtype=dtype).tobytes()
        if self.kind in ("snorm", "sint"):
            dtype = {8: np.int8, 16: np.int16, 32: np.int32}[self.bits]
            return np.full(n, value, dtype=dtype).tobytes()
        if self.kind == "sfloat":
            dtype = {16: np.float16, 32: np.float32}[self.bits]
            return np.full(n, value, dtype=dtype).tobytes()
        if self.kind == "depth_sfloat":
            return np.full(n, value / 65536.0, dtype=np.float32).tobytes()
        raise ValueError(self.kind)

    def decode(self, data: bytes) -> np.ndarray:
        """Per-component integer values of packed texels (int64 array, -1 where not integral)."""
        if self.kind in ("unorm", "srgb", "uint", "depth_unorm"):
            dtype = {8: np.uint8, 16: np.uint16, 32: np.uint32}[self.bits]
            return np.frombuffer(data, dtype=dtype).astype(np.int64)
        if self.kind in ("snorm", "sint"):
            dtype = {8: np.int8, 16: np.int16, 32: np.int32}[self.bits]
            return np.frombuffer(data, dtype=dtype).astype(np.int64)
        raw = np.frombuffer(data, dtype={16: np.float16, 32: np.float32}[self.bits]).astype(np.float64)
        if self.kind == "depth_sfloat":
            raw = raw * 65536.0
        out = np.rint(raw)
        return np.where(out == raw, out, -1).astype(np.int64)


@cache
def codec(format_name: str) -> Codec | None:
    """The probe codec of a format, or None when the probe cannot hold exact values in it."""
    info = formats.lookup(format_name)
    if info.compressed or info.packed_bits or info.is_planar or info.chroma:
        return None
    if info.has_depth:
        if info.has_stencil:
            return None
        if info.vk_name == "D16_UNORM":
            return Codec("depth_unorm", 16, 1, 1 << 16)
        if info.vk_name == "D32_SFLOAT":
            return Codec("depth_sfloat", 32, 1, 1 << 16)
        return None
    comps = info.components
    if not comps or info.has_stencil:
        return None
    bits = {c[1] for c in comps}
    numerics = {c[2] for c in comps}
    if len(bits) != 1:
        return None
    (b,) = bits
    if b not in (8, 16, 32):
        return None
    if info.is_srgb:
        return Codec("srgb", 8, len(comps), 256) if b == 8 else None
    if len(numerics) != 1:
        return None
    (numeric,) = numerics
    n = len(comps)
    table = {
        ("UNORM", 8): 256, ("UNORM", 16): 1 << 16,
        ("SNORM", 8): 128, ("SNORM", 16): 1 << 15,
        ("SFLOAT", 16): 2048, ("SFLOAT", 32): 1 << 16,
        ("UINT", 8): 256, ("UINT", 16): 1 << 16, ("UINT", 32): 1 << 30,
        ("SINT", 8): 128, ("SINT", 16): 1 << 15, ("SINT", 32): 1 << 30,
    }
    if (numeric, b) not in table:
        return None
    return Codec(numeric.lower(), b, n, table[(numeric, b)])


def seed(pass_index: int, k: int) -> int:
    """The constant a pass adds to its k-th written subresource."""
    return ((pass_index + 1) * 40503 + k * 977 + 13) & UINT32


def initial_value(resource_name: str, modulus: int) -> int:
    """The value the runtime stores in persistent/imported resources at creation."""
    h = 5381
    for ch in resource_name.encode():
        h = (h * 33 + ch) & UINT32
    return h % modulus


def has_header(resource: dict) -> bool:
    return resource["kind"] == "buffer" and "indirect" in resource.get("usages", [])


def header_words(plan_size: tuple[int, int]) -> list[int]:
    """Indirect arguments: draw (3,1,0,0), indexed draw (3,1,0,0,0), dispatch over the plan size."""
    gx, gy = max(1, -(-int(plan_size[0]) // 8)), max(1, -(-int(plan_size[1]) // 8))
    words = [0] * HEADER_WORDS
    words[0:4] = [3, 1, 0, 0]
    words[4:9] = [3, 1, 0, 0, 0]
    words[12:15] = [gx, gy, 1]
    return words


def modulus(resource: dict) -> int | None:
    if resource["kind"] == "buffer":
        return BUFFER_MODULUS
    c = codec(resource["format"])
    return c.modulus if c else None
