"""Read a YAML file into plain Python values plus a map of where each key and value sits.

Nothing in the file is executed: only the YAML 1.2 core schema (mappings, sequences,
strings, ints, floats, bools, null) is accepted; any explicit tag (``!!python/object``,
``!foo``) is an error. Duplicate keys, non-UTF-8 bytes and syntax errors are errors with
the line and column where they occur.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ruamel.yaml import YAML
from ruamel.yaml.error import MarkedYAMLError, YAMLError
from ruamel.yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from rgraph.errors import Location, RGraphError

PathKey = tuple[str | int, ...]

_CORE = "tag:yaml.org,2002:"
_MAX_NODES = 1_000_000  # guards against alias bombs
_MAX_BYTES = 16 * 1024 * 1024
_INT = re.compile(r"^[-+]?(0|[1-9][0-9_]*)$|^0x[0-9a-fA-F_]+$|^0o[0-7_]+$")


@dataclass
class SourceMap:
    """Locations of values (by path) and of mapping keys (by path of the value)."""

    file: str
    values: dict[PathKey, Location] = field(default_factory=dict)
    keys: dict[PathKey, Location] = field(default_factory=dict)
    lines: list[str] = field(default_factory=list)

    def value(self, path: PathKey) -> Location:
        """Location of the value at ``path``, or of its nearest located ancestor."""
        for n in range(len(path), -1, -1):
            loc = self.values.get(path[:n])
            if loc is not None:
                return loc
        return Location(self.file, 1, 1)

    def key(self, path: PathKey) -> Location:
        """Location of the key naming the value at ``path`` (falls back to the value)."""
        return self.keys.get(path) or self.value(path)

    def inside_value(self, path: PathKey, offset: int) -> Location:
        """Location ``offset`` characters into the scalar at ``path`` (skipping its quote)."""
        loc = self.value(path)
        line = self.lines[loc.line - 1] if 0 < loc.line <= len(self.lines) else ""
        quoted = loc.col - 1 < len(line) and line[loc.col - 1] in "'\""
        return Location(loc.file, loc.line, loc.col + offset + (1 if quoted else 0))

    def error(self, path: PathKey, message: str, *, at_key: bool = False) -> RGraphError:
        return RGraphError.at(self.key(path) if at_key else self.value(path), message)


def _loc(file: str, node: Node) -> Location:
    return Location(file, node.start_mark.line + 1, node.start_mark.column + 1)


def read_text(path: Path, display: str) -> str:
    """Read ``path`` as UTF-8, reporting the line and column of the first bad byte."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise RGraphError.in_file(display, "no such file") from None
    except IsADirectoryError:
        raise RGraphError.in_file(display, "is a directory, expected a YAML file") from None
    except OSError as exc:
        raise RGraphError.in_file(display, f"cannot read: {exc.strerror}") from None
    if len(data) > _MAX_BYTES:
        raise RGraphError.in_file(display, f"file is larger than {_MAX_BYTES // (1024 * 1024)} MiB")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[: exc.start]
        line = before.count(b"\n") + 1
        col = len(before) - (before.rfind(b"\n") + 1) + 1
        raise RGraphError.in_file(
            display, f"file is not valid UTF-8 (byte 0x{data[exc.start]:02x})", line, col
        ) from None


def load_yaml(path: Path, display: str | None = None) -> tuple[Any, SourceMap]:
    """Parse ``path`` into plain values and a :class:`SourceMap`."""
    shown = display or str(path)
    text = read_text(path, shown)
    if text.startswith("\ufeff"):
        text = text[1:]
    try:
        node = YAML(typ="rt").compose(text)
    except MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (1, 1)
        problem = exc.problem or exc.context or "invalid YAML"
        raise RGraphError.in_file(shown, f"YAML syntax error: {problem}", line, col) from None
    except YAMLError as exc:
        raise RGraphError.in_file(shown, f"YAML syntax error: {exc}") from None
    smap = SourceMap(shown, lines=text.splitlines())
    if node is None:
        return None, smap
    builder = _Builder(shown, smap)
    return builder.build(node, ()), smap


class _Builder:
    def __init__(self, file: str, smap: SourceMap) -> None:
        self.file = file
        self.smap = smap
        self.count = 0

    def build(self, node: Node, path: PathKey) -> Any:
        self.count += 1
        if self.count > _MAX_NODES:
            raise RGraphError.at(_loc(self.file, node), "document too large (alias expansion?)")
        self.smap.values.setdefault(path, _loc(self.file, node))
        tag = str(node.tag)
        if isinstance(node, MappingNode):
            self._check_tag(node, tag, "map")
            return self._mapping(node, path)
        if isinstance(node, SequenceNode):
            self._check_tag(node, tag, "seq")
            return [self.build(item, (*path, i)) for i, item in enumerate(node.value)]
        assert isinstance(node, ScalarNode)
        return self._scalar(node, tag)

    def _check_tag(self, node: Node, tag: str, kind: str) -> None:
        if tag != _CORE + kind:
            raise RGraphError.at(_loc(self.file, node), f"YAML tag '{_short(tag)}' is not allowed (plain values only)")

    def _mapping(self, node: MappingNode, path: PathKey) -> dict[str, Any]:
        out: dict[str, Any] = {}
        seen: dict[str, Location] = {}
        for key_node, value_node in node.value:
            key_loc = _loc(self.file, key_node)
            if str(key_node.tag) == _CORE + "merge":
                raise RGraphError.at(key_loc, "YAML merge keys ('<<') are not supported")
            if not isinstance(key_node, ScalarNode):
                raise RGraphError.at(key_loc, "mapping keys must be plain strings")
            key = self._scalar(key_node, str(key_node.tag))
            if isinstance(key, bool) or key is None:
                key = key_node.value  # `on:`/`null:` as a name, not a bool
            key = str(key)
            if key in seen:
                first = seen[key]
                raise RGraphError.at(key_loc, f"duplicate key '{key}' (first defined at line {first.line})")
            seen[key] = key_loc
            self.smap.keys[(*path, key)] = key_loc
            out[key] = self.build(value_node, (*path, key))
        return out

    def _scalar(self, node: ScalarNode, tag: str) -> Any:
        text = node.value
        if tag == _CORE + "str":
            return text
        if tag == _CORE + "null":
            return None
        if tag == _CORE + "bool":
            return text.lower() == "true"
        if tag == _CORE + "int":
            cleaned = text.replace("_", "")
            if not _INT.match(text):
                return text
            return int(cleaned, 0) if cleaned[:2] in ("0x", "0o") else int(cleaned)
        if tag == _CORE + "float":
            low = text.lower().replace("_", "")
            if low in (".inf", "+.inf"):
                return math.inf
            if low == "-.inf":
                return -math.inf
            if low == ".nan":
                return math.nan
            return float(low)
        raise RGraphError.at(_loc(self.file, node), f"YAML tag '{_short(tag)}' is not allowed (plain values only)")


def _short(tag: str) -> str:
    return "!!" + tag[len(_CORE):] if tag.startswith(_CORE) else tag
