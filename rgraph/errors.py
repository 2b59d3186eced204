"""The one error type for bad user input: it carries file, line and column.

The command line prints ``FILE:LINE:COL: error: message`` for each and exits 2.
Lines and columns are 1-based, as editors show them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class Location:
    """A place in a source file (1-based line and column)."""

    file: str
    line: int = 1
    col: int = 1

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


@dataclass
class Diagnostic:
    location: Location
    message: str

    def __str__(self) -> str:
        return f"{self.location}: error: {self.message}"


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

    @property
    def first(self) -> Diagnostic:
        return self.diagnostics[0]
