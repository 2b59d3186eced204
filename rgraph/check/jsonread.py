"""Decode a plan (or any rgraph JSON file) with limits: the checker's own, safe ``json.loads``.

Python's decoder recurses per nesting level (100,000 brackets are a RecursionError),
converts integers of any length (over 4,300 digits a ValueError) and accepts ``NaN`` and
``Infinity``. Here nesting is bounded before decoding, integers are 64-bit, numbers are
finite, and every refusal is an ``RGraphError`` at the line and column of the culprit.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from rgraph.errors import CONTROL, RGraphError, quote
from rgraph.files import check_bracket_depth, line_col, read_text

MAX_PLAN_BYTES = 256 * 1024 * 1024
MAX_DEPTH = 64
_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{}]')


def decode_json(text: str, file: str) -> Any:
    """``json.loads(text)`` within the limits above; located ``RGraphError`` otherwise."""
    check_bracket_depth(text, file, MAX_DEPTH, _TOKEN, "JSON")

    def refuse(message: str, literal: str) -> RGraphError:
        offset = text.find(literal)
        return RGraphError.in_file(file, message, *line_col(text, max(offset, 0)))

    def parse_int(literal: str) -> int:
        if len(literal.lstrip("-")) > 19 or not -(2**63) <= int(literal) < 2**64:
            raise refuse(f"integer out of range ({len(literal)} digits; at most 64 bits)", literal)
        return int(literal)

    def parse_float(literal: str) -> float:
        value = float(literal)
        if value in (float("inf"), float("-inf")):
            raise refuse(f"number {literal[:40]} is out of range", literal)
        return value

    def parse_constant(literal: str) -> float:
        raise refuse(f"'{literal}' is not JSON (numbers must be finite)", literal)

    def check(item: Any) -> None:
        if isinstance(item, str) and CONTROL.search(item):
            raise refuse(f"text {quote(item)} contains a control character or a lone surrogate",
                         json.dumps(item)[1:-1])
        if isinstance(item, list):
            for sub in item:
                if not isinstance(sub, dict):
                    check(sub)

    def checked_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        for key, value in pairs:
            check(key)
            check(value)
        return dict(pairs)

    try:
        return json.loads(text, parse_int=parse_int, parse_float=parse_float, parse_constant=parse_constant,
                          object_pairs_hook=checked_pairs)
    except json.JSONDecodeError as exc:
        raise RGraphError.in_file(file, f"invalid JSON: {exc.msg}", exc.lineno, exc.colno) from None
    except RecursionError:  # unreachable after the depth check; kept as a last guard
        raise RGraphError.in_file(file, f"JSON nested deeper than {MAX_DEPTH} levels") from None


def read_json(path: str | Path, what: str = "a plan JSON file", limit: int = MAX_PLAN_BYTES) -> tuple[Any, str]:
    """The decoded contents of the regular file ``path`` and its text."""
    text = read_text(Path(path), str(path), what, limit)
    return decode_json(text, str(path)), text
