"""Read MiniMalloc CSV traces (``id,lower,upper,size[,alignment]``, ``upper`` exclusive)."""

from __future__ import annotations

import csv
from pathlib import Path

from rgraph.errors import RGraphError, quote
from rgraph.memory.model import Block

REQUIRED_COLUMNS = ("id", "lower", "upper", "size")
DEFAULT_CLASS = "trace"
MAX_TRACE_BYTES = 64 * 1024 * 1024
MAX_ID_CHARS = 1024
MAX_VALUE = 2**62  # sizes, times and alignments: 64-bit arithmetic with room to add


def read_trace(path: str | Path, memory_class: str = DEFAULT_CLASS) -> list[Block]:
    """Blocks of a MiniMalloc trace: ``end = upper - 1``; alignment 1 unless a column says."""
    from rgraph.files import read_text

    path = Path(path)
    text = read_text(path, str(path), "a CSV trace", MAX_TRACE_BYTES)
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise RGraphError.in_file(path, "empty trace: expected a header 'id,lower,upper,size'")
    header = [h.strip() for h in _cells(path, lines[0], 1)]
    for column in REQUIRED_COLUMNS:
        if column not in header:
            raise RGraphError.in_file(
                path, f"header lacks column {quote(column)} (expected 'id,lower,upper,size[,alignment]')"
            )
    index = {name: k for k, name in enumerate(header)}
    blocks: list[Block] = []
    seen: dict[str, int] = {}
    for line_no, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = _cells(path, line, line_no)
        if len(cells) != len(header):
            raise RGraphError.in_file(
                path, f"expected {len(header)} columns, found {len(cells)}", line_no, 1
            )
        starts = _cell_columns(line)

        def number(column: str, minimum: int, cells=cells, starts=starts, line_no=line_no) -> int:
            k = index[column]
            raw = cells[k].strip()
            if len(raw) > 24 and raw.lstrip("+-").isdigit():
                raise RGraphError.in_file(path, f"{column} out of range ({len(raw)} digits; at most 2**62)",
                                          line_no, starts[k])
            try:
                value = int(raw) if len(raw) <= 24 else None
                if value is None:
                    raise ValueError(raw)
            except ValueError:
                raise RGraphError.in_file(
                    path, f"{column} must be an integer, got {quote(raw)}", line_no, starts[k]
                ) from None
            if not minimum <= value <= MAX_VALUE:
                bound = f">= {minimum}" if value < minimum else "at most 2**62"
                raise RGraphError.in_file(path, f"{column} must be {bound}, got {value}", line_no, starts[k])
            return value

        name = cells[index["id"]].strip()
        if not name:
            raise RGraphError.in_file(path, "empty id", line_no, starts[index["id"]])
        if len(name) > MAX_ID_CHARS:
            raise RGraphError.in_file(path, f"id of {len(name):,} characters (the limit is {MAX_ID_CHARS:,})",
                                      line_no, starts[index["id"]])
        if name in seen:
            raise RGraphError.in_file(
                path, f"duplicate id {quote(name)} (first on line {seen[name]})", line_no, starts[index["id"]]
            )
        seen[name] = line_no
        lower = number("lower", 0)
        upper = number("upper", 0)
        if upper <= lower:
            raise RGraphError.in_file(
                path, f"upper ({upper}) must be greater than lower ({lower})", line_no, starts[index["upper"]]
            )
        size = number("size", 0)
        alignment = number("alignment", 1) if "alignment" in index else 1
        blocks.append(Block(name, lower, upper - 1, size, alignment, memory_class))
    return blocks


def _cells(path: Path, line: str, line_no: int) -> list[str]:
    """The comma-separated cells of one line (the csv module's field limit is a located error)."""
    try:
        return next(csv.reader([line]))
    except csv.Error as exc:
        raise RGraphError.in_file(path, f"malformed CSV line: {exc}", line_no, 1) from None


def _cell_columns(line: str) -> list[int]:
    """1-based column where each comma-separated cell starts (traces have no quoting)."""
    columns, col = [1], 1
    for ch in line:
        col += 1
        if ch == ",":
            columns.append(col)
    return columns
