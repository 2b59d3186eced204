"""Small text formatters shared by every view: bytes, ranges, sync states."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

KIB = 1024
MIB = 1024 * 1024
GIB = 1024 * 1024 * 1024

# Usages that write their resource (FORMAT.md usage table); used when an access lacks "write".
WRITE_USAGES = frozenset(
    {
        "color_attachment",
        "color_attachment_blend",
        "depth_attachment",
        "storage_write",
        "storage_rw",
        "transfer_dst",
        "accel_build",
    }
)


def human_bytes(n: int | None) -> str:
    """``n`` bytes in binary units with one decimal: ``8.0 MiB``, ``126.6 KiB``, ``128 B``."""
    if n is None:
        return "-"
    if abs(n) >= GIB:
        return f"{n / GIB:.1f} GiB"
    if abs(n) >= MIB:
        return f"{n / MIB:.1f} MiB"
    if abs(n) >= KIB:
        return f"{n / KIB:.1f} KiB"
    return f"{n} B"


def bytes_exact(n: int | None) -> str:
    """Human units followed by the exact count: ``8.0 MiB (8388608 B)``."""
    if n is None:
        return "-"
    human = human_bytes(n)
    return human if human == f"{n} B" else f"{human} ({n} B)"


def align_up(value: int, alignment: int) -> int:
    """The smallest multiple of ``alignment`` (>= 1) that is >= ``value``."""
    alignment = max(alignment, 1)
    return -(-value // alignment) * alignment


def percent(part: float, whole: float) -> str:
    """``part / whole`` as a percentage with one decimal (``-`` when ``whole`` is 0)."""
    return f"{100.0 * part / whole:.1f}%" if whole else "-"


def half_open(r: Sequence[int]) -> str:
    """A half-open range ``[a, b)`` as ``a:b``."""
    return f"{r[0]}:{r[1]}"


def subresource(sub: Mapping[str, Any] | None) -> str:
    """``[mips 0:1 layers 0:4]`` for an image range, empty for buffers (``None``)."""
    if not sub:
        return ""
    parts = []
    if sub.get("mips") is not None:
        parts.append(f"mips {half_open(sub['mips'])}")
    if sub.get("layers") is not None:
        parts.append(f"layers {half_open(sub['layers'])}")
    return f"[{' '.join(parts)}]" if parts else ""


def flags(names: Sequence[str] | None) -> str:
    """A sorted flag list joined with ``|``; ``NONE`` when empty."""
    return "|".join(names) if names else "NONE"


def sync_state(state: Mapping[str, Any]) -> str:
    """``STAGES/ACCESS/LAYOUT`` of one side of a barrier (no layout segment for buffers)."""
    text = f"{flags(state.get('stages'))}/{flags(state.get('access'))}"
    layout = state.get("layout")
    return f"{text}/{layout}" if layout is not None else text


def extent(ext: Sequence[int] | None) -> str:
    """``1920x1080`` (depth shown only when it is not 1)."""
    if not ext:
        return "-"
    dims = list(ext)
    if len(dims) == 3 and dims[2] == 1:
        dims = dims[:2]
    return "x".join(str(d) for d in dims)


def is_write(access: Mapping[str, Any]) -> bool:
    """Whether an access writes; falls back to its usage when ``write`` is absent."""
    if "write" in access and access["write"] is not None:
        return bool(access["write"])
    return access.get("usage") in WRITE_USAGES


def reads_too(access: Mapping[str, Any]) -> bool:
    """Whether an access reads (a read-modify-write such as ``depth_attachment`` does)."""
    if not is_write(access):
        return True
    return any("READ" in a for a in access.get("access") or ())


def plural(count: int, noun: str) -> str:
    """``1 heap``, ``3 heaps``."""
    if count == 1:
        return f"{count} {noun}"
    return f"{count} {noun}es" if noun.endswith(("s", "sh", "ch", "x")) else f"{count} {noun}s"


def param_value(value: Any) -> str:
    """A parameter value as JSON would spell it (``true``, ``8``, ``"name"``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    return str(value)
