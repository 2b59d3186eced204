"""Read a YAML file into plain Python values plus a map of where each key and value sits.

Nothing in the file is executed: only the YAML 1.2 core schema (mappings, sequences,
strings, ints, floats, bools, null) is accepted; any explicit tag (``!!python/object``,
``!foo``, ``!!int``) is an error. Duplicate keys, non-UTF-8 bytes and syntax errors are errors
with the line and column where they occur; the limits on size, depth and aliases are in
:mod:`rgraph.spec.yaml_events`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ruamel.yaml import YAML
from ruamel.yaml.error import MarkedYAMLError, YAMLError

from rgraph.errors import Location, RGraphError, escape
from rgraph.files import read_text
from rgraph.spec.yaml_events import EventBuilder, PathKey, check_flow_depth


@dataclass
class SourceMap:
    """Locations of values (by path) and of mapping keys (by path of the value)."""

    file: str
    values: dict[PathKey, Location] = field(default_factory=dict)
    keys: dict[PathKey, Location] = field(default_factory=dict)
    lines: list[str] = field(default_factory=list)
    via: Location | None = None  # where this file was included, for included files

    def value(self, path: PathKey) -> Location:
        """Location of the value at ``path``, or of its nearest located ancestor."""
        for n in range(len(path), -1, -1):
            loc = self.values.get(path[:n])
            if loc is not None:
                return self._via(loc)
        return self._via(Location(self.file, 1, 1))

    def key(self, path: PathKey) -> Location:
        """Location of the key naming the value at ``path`` (falls back to the value)."""
        loc = self.keys.get(path)
        return self._via(loc) if loc is not None else self.value(path)

    def _via(self, loc: Location) -> Location:
        return loc if self.via is None or loc.via is not None else replace(loc, via=self.via)

    def inside_value(self, path: PathKey, offset: int) -> Location:
        """Location ``offset`` characters into the scalar at ``path`` (skipping its quote)."""
        loc = self.value(path)
        line = self.lines[loc.line - 1] if 0 < loc.line <= len(self.lines) else ""
        quoted = loc.col - 1 < len(line) and line[loc.col - 1] in "'\""
        return replace(loc, col=loc.col + offset + (1 if quoted else 0))

    def error(self, path: PathKey, message: str, *, at_key: bool = False) -> RGraphError:
        return RGraphError.at(self.key(path) if at_key else self.value(path), message)


def load_yaml(path: Path, display: str | None = None) -> tuple[Any, SourceMap]:
    """Parse ``path`` into plain values and a :class:`SourceMap`."""
    shown = display or str(path)
    return parse_yaml_text(read_text(path, shown), shown)


def parse_yaml_text(text: str, shown: str) -> tuple[Any, SourceMap]:
    """Parse YAML ``text`` (from the file ``shown``) into plain values and a :class:`SourceMap`."""
    if text.startswith("\ufeff"):
        text = text[1:]
    check_flow_depth(text, shown)
    builder = EventBuilder(shown)
    try:
        _, value = builder.build(YAML(typ="rt").parse(text))
    except MarkedYAMLError as exc:
        raise RGraphError.at(_mark_location(shown, exc), f"YAML syntax error: {_problem(exc)}") from None
    except YAMLError as exc:  # the reader's errors (control characters) carry a position, not a mark
        raise RGraphError.at(_reader_location(shown, text, exc), f"YAML syntax error: {_one_line(exc)}") from None
    smap = SourceMap(shown, lines=text.splitlines())
    for path, loc in builder.values:
        smap.values.setdefault(path, loc)
    smap.keys.update(builder.keys)
    return value, smap


def _mark_location(file: str, exc: MarkedYAMLError) -> Location:
    mark = exc.problem_mark or exc.context_mark
    return Location(file, mark.line + 1, mark.column + 1) if mark else Location(file)


def _problem(exc: MarkedYAMLError) -> str:
    return _one_line(exc.problem or exc.context or "invalid YAML")


def _reader_location(file: str, text: str, exc: YAMLError) -> Location:
    position = getattr(exc, "position", None)
    if not isinstance(position, int):
        return Location(file)
    line = text.count("\n", 0, position) + 1
    return Location(file, line, position - (text.rfind("\n", 0, position) + 1) + 1)


def _one_line(exc: object) -> str:
    character = getattr(exc, "character", None)
    if isinstance(character, int):
        return f"control character U+{character:04X} is not allowed (write it as an escape in a double-quoted string)"
    return escape(" ".join(str(exc).split()))
