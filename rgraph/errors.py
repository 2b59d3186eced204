"""The one error type for bad user input: it carries file, line and column.

The command line prints ``FILE:LINE:COL: error: message`` for each and exits 2.
Lines and columns are 1-based, as editors show them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path

# C0/C1 controls, DEL, lone surrogates, bidi overrides: never reach the terminal verbatim
_UNSAFE = re.compile("[\x00-\x1f\x7f-\x9f\ud800-\udfff\u202a-\u202e\u2066-\u2069]")
# what no rgraph file may contain in its text (tab and newline are fine): terminal escapes and the like
CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069\ud800-\udfff]")
QUOTE_LIMIT = 60
MESSAGE_LIMIT = 2000


def escape(text: str) -> str:
    """``text`` with control characters, surrogates and bidi overrides as ``\\xNN``/``\\uNNNN``."""
    def one(match: re.Match[str]) -> str:
        code = ord(match.group())
        return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"

    return _UNSAFE.sub(one, text)


def quote(value: object, limit: int = QUOTE_LIMIT) -> str:
    """``'value'`` for a message: escaped (one line, no terminal escapes) and cut to ``limit``;
    a non-string as its (cut) repr, without quotes."""
    if not isinstance(value, str):
        text = repr(value) if not isinstance(value, int) or value.bit_length() < 4000 else "a huge integer"
        return escape(text if len(text) <= limit else text[:limit] + "...")
    text = value
    if len(text) <= limit:
        return f"'{escape(text)}'"
    return f"'{escape(text[:limit])}...' ({len(text):,} characters)"


@dataclass(frozen=True)
class Location:
    """A place in a source file (1-based line and column)."""

    file: str
    line: int = 1
    col: int = 1
    via: Location | None = field(default=None, compare=False)  # the include site, for included files

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"

    def include_chain(self) -> str:
        """``" (included from a.yaml:3:11, included from ...)"`` or ``""``."""
        sites = []
        at = self.via
        while at is not None and len(sites) < 64:
            sites.append(f"included from {at}")
            at = at.via
        if len(sites) > 4:
            sites = [*sites[:3], f"... ({len(sites) - 4} more)", sites[-1]]
        return f" ({', '.join(sites)})" if sites else ""


@dataclass
class Diagnostic:
    location: Location
    message: str

    def __str__(self) -> str:
        message = self.message if len(self.message) <= MESSAGE_LIMIT else self.message[:MESSAGE_LIMIT] + "..."
        return escape(f"{self.location}: error: {message}{self.location.include_chain()}")


@dataclass
class RGraphError(Exception):
    """Bad input: one or more diagnostics, each with a location."""

    diagnostics: list[Diagnostic] = field(default_factory=list)

    @classmethod
    def at(cls, location: Location, message: str) -> RGraphError:
        return cls([Diagnostic(location, message)])

    @classmethod
    def in_file(cls, file: str | Path, message: str, line: int = 1, col: int = 1) -> RGraphError:
        return cls([Diagnostic(Location(str(file), line, col), message)])

    def __str__(self) -> str:
        return "\n".join(str(d) for d in self.diagnostics)

    def included_from(self, file: str, site: Location) -> RGraphError:
        """This error with ``site`` as the include site of its diagnostics in ``file``."""
        for d in self.diagnostics:
            if d.location.file == file and d.location.via is None:
                d.location = replace(d.location, via=site)
        return self

    @property
    def first(self) -> Diagnostic:
        return self.diagnostics[0]
