"""Read MiniMalloc CSV traces (``id,lower,upper,size[,alignment]``, ``upper`` exclusive)."""

from __future__ import annotations

import csv
from pathlib import Path

from rgraph.errors import RGraphError, quote
from rgraph.memory.model import Block

REQUIRED_COLUMNS = ("id", "lower", "upper", "size")
DEFAULT_CLASS = "trace"


def read_trace(path: str | Path, memory_class: str = DEFAULT_CLASS) -> list[Block]:
    """Blocks of a MiniMalloc trace: ``end = upper - 1``; alignment 1 unless a column says."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise RGraphError.in_file(path, f"cannot read trace: {exc}") from None
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise RGraphError.in_file(path, "empty trace: expected a header 'id,lower,upper,size'")
    header = [h.strip() for h in next(csv.reader([lines[0]]))]
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
        cells = next(csv.reader([line]))
        if len(cells) != len(header):
            raise RGraphError.in_file(
                path, f"expected {len(header)} columns, found {len(cells)}", line_no, 1
            )
        starts = _cell_columns(line)

        def number(column: str, minimum: int, cells=cells, starts=starts, line_no=line_no) -> int:
            k = index[column]
            raw = cells[k].strip()
            try:
                value = int(raw)
            except ValueError:
                raise RGraphError.in_file(
                    path, f"{column} must be an integer, got {quote(raw)}", line_no, starts[k]
                ) from None
            if value < minimum:
                raise RGraphError.in_file(
                    path, f"{column} must be >= {minimum}, got {value}", line_no, starts[k]
                )
            return value

        name = cells[index["id"]].strip()
        if not name:
            raise RGraphError.in_file(path, "empty id", line_no, starts[index["id"]])
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


def _cell_columns(line: str) -> list[int]:
    """1-based column where each comma-separated cell starts (traces have no quoting)."""
    columns, col = [1], 1
    for ch in line:
        col += 1
        if ch == ",":
            columns.append(col)
    return columns
