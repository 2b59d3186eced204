"""Vulkan formats as graph files name them, with their registry facts and compile-time features.

The data lives in ``table.py``, generated from the Vulkan registry by ``tools/gen_formats.py``;
its docstring states how usage features are derived. Devices report real support at run time.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

from rgraph.formats import table

#: The usage vocabulary of FORMAT.md section 1 (closed).
USAGES = frozenset({
    "color_attachment", "color_attachment_blend", "depth_attachment", "depth_read", "sampled",
    "storage_read", "storage_write", "storage_rw", "uniform", "vertex", "index", "indirect",
    "transfer_src", "transfer_dst", "accel_build", "accel_read",
})

_VK_PREFIX = "vk_format_"


@dataclass(frozen=True)
class FormatInfo:
    """One VkFormat: registry facts plus the usages a graph may put it to."""

    name: str  # user name, e.g. "d32_sfloat"
    vk_name: str  # enum name without VK_FORMAT_, e.g. "D32_SFLOAT"
    value: int  # VkFormat enum value
    block_bytes: int  # bytes per texel block
    block_extent: tuple[int, int, int]  # texels per block in x, y, z ((1, 1, 1) if uncompressed)
    has_depth: bool
    has_stencil: bool
    is_color: bool
    is_srgb: bool
    compressed: bool
    numeric: str  # numeric type of the first component: UNORM, SFLOAT, SRGB, ...
    texels_per_block: int = 1
    components: tuple[tuple[str, int, str], ...] = ()  # (type, bits or 0 if compressed, numeric)
    compression: str | None = None  # "BC", "ETC2", "ASTC LDR", ... or None
    packed_bits: int | None = None  # PACKnn formats
    chroma: str | None = None  # "420", "422", "444" for Y'CbCr formats
    plane_count: int = 1
    spirv_image_format: str | None = None  # SPIR-V image format name, e.g. "Rgba16f"
    features: frozenset[str] = frozenset()

    @property
    def is_planar(self) -> bool:
        return self.plane_count > 1

    @property
    def vk_enum_name(self) -> str:
        return "VK_FORMAT_" + self.vk_name

    def supports(self, usage: str) -> bool:
        """Whether a resource of this format may be used as ``usage`` (FORMAT.md vocabulary).

        Buffer- and acceleration-structure-only usages (uniform, vertex, ...) are False.
        Raises ValueError for a word outside the vocabulary.
        """
        if usage not in USAGES:
            raise ValueError(f"unknown usage {usage!r}; expected one of {', '.join(sorted(USAGES))}")
        return usage in self.features


def _make(row: dict) -> FormatInfo:
    fields = dict(row)
    fields["features"] = frozenset(row["features"])
    return FormatInfo(**fields)


@cache
def _by_name() -> dict[str, FormatInfo]:
    return {row["name"]: _make(row) for row in table.FORMATS}


@cache
def _by_value() -> dict[int, FormatInfo]:
    return {info.value: info for info in _by_name().values()}


def lookup(name: str) -> FormatInfo:
    """The format named ``name``: case-insensitive, with or without ``VK_FORMAT_``; aliases accepted.

    Raises KeyError (message naming the input) when there is no such format.
    """
    key = name.strip().lower()
    key = key.removeprefix(_VK_PREFIX)
    key = table.ALIASES.get(key, key)
    try:
        return _by_name()[key]
    except KeyError:
        raise KeyError(f"unknown format {name!r}") from None


def from_value(value: int) -> FormatInfo:
    """The format with VkFormat enum value ``value``; raises KeyError."""
    try:
        return _by_value()[value]
    except KeyError:
        raise KeyError(f"unknown VkFormat value {value}") from None


def names() -> list[str]:
    """All valid user names (canonical, sorted), for did-you-mean messages."""
    return sorted(_by_name())


def all_formats() -> list[FormatInfo]:
    """Every format, sorted by user name."""
    return [_by_name()[n] for n in names()]
