"""Find where a value sits in JSON text, given its path (keys and list indices).

Used when a plan is malformed (rgraph.plan.load, rgraph check), to turn a path like ``passes[3].barriers[0].src``
into the 1-based line and column an editor shows.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from json.decoder import scanstring

_DECODER = json.JSONDecoder()
_WHITESPACE = " \t\r\n"

PathPart = str | int


def _skip_ws(text: str, pos: int) -> int:
    while pos < len(text) and text[pos] in _WHITESPACE:
        pos += 1
    return pos


def _value_end(text: str, pos: int) -> int:
    _, end = _DECODER.raw_decode(text, pos)
    return end


def _child_offset(text: str, pos: int, part: PathPart) -> int | None:
    """Offset of the member ``part`` of the container value starting at ``pos``."""
    if isinstance(part, str) and text.startswith("{", pos):
        pos = _skip_ws(text, pos + 1)
        while pos < len(text) and text[pos] == '"':
            key, pos = scanstring(text, pos + 1)
            pos = _skip_ws(text, pos)
            pos = _skip_ws(text, pos + 1)  # the colon
            if key == part:
                return pos
            pos = _skip_ws(text, _value_end(text, pos))
            if pos < len(text) and text[pos] == ",":
                pos = _skip_ws(text, pos + 1)
        return None
    if isinstance(part, int) and text.startswith("[", pos):
        pos = _skip_ws(text, pos + 1)
        for _ in range(part):
            if pos >= len(text) or text[pos] == "]":
                return None
            pos = _skip_ws(text, _value_end(text, pos))
            if pos < len(text) and text[pos] == ",":
                pos = _skip_ws(text, pos + 1)
        if pos >= len(text) or text[pos] == "]":
            return None
        return pos
    return None


def line_col(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    col = offset - (text.rfind("\n", 0, offset) + 1) + 1
    return line, col


def locate(text: str, path: Sequence[PathPart]) -> tuple[int, int]:
    """Line and column of the deepest value along ``path`` that exists in ``text``."""
    try:
        pos = _skip_ws(text, 0)
        for part in path:
            child = _child_offset(text, pos, part)
            if child is None:
                break
            pos = child
    except (ValueError, IndexError):
        return 1, 1
    return line_col(text, pos)


def format_path(path: Sequence[PathPart]) -> str:
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out or "top level"


_PATH_PART = re.compile(r"\[(\d+)\]|([^.\[\]]+)")


def path_parts(where: str) -> list[PathPart]:
    """``passes[3].src`` -> ``["passes", 3, "src"]`` (``top level`` -> ``[]``)."""
    if where == "top level":
        return []
    return [int(index) if index else key for index, key in _PATH_PART.findall(where)]
