"""Build plain Python values from ruamel's YAML event stream, with every limit checked as it goes.

Composing from events (instead of ruamel's recursive composer) lets the limits act before
memory or the stack explode: nesting depth, the number of values, alias expansion (an alias
costs the size of what it names, counted when it is used), recursive and undefined aliases.
Only the YAML 1.2 core schema is read: any explicit tag, a ``%YAML`` directive other than
1.2 and ``%TAG`` directives are errors, so ``!!int abc`` or 1.1's ``yes``/sexagesimal
numbers never change what a value means.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from ruamel.yaml import events as ev

from rgraph.errors import CONTROL, Location, RGraphError, quote
from rgraph.files import check_bracket_depth

PathKey = tuple[str | int, ...]

MAX_DEPTH = 64
MAX_NODES = 500_000
MAX_ALIAS_NODES = 100_000
MAX_KEYS = 20_000  # per mapping: a 16,000-pass graph has 16,000 (parsing costs ~10-50 us a value)
MAX_INT_BITS = 64

_NULL = frozenset(("", "~", "null", "Null", "NULL"))
_TRUE = frozenset(("true", "True", "TRUE"))
_FALSE = frozenset(("false", "False", "FALSE"))
_DEC = re.compile(r"[-+]?(0|[1-9][0-9]*)")
_HEX = re.compile(r"0x[0-9a-fA-F]+")
_OCT = re.compile(r"0o[0-7]+")
_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?")
_SPECIAL_FLOAT = {
    **{sign + word: float(sign + "inf") for sign in ("", "+", "-") for word in (".inf", ".Inf", ".INF")},
    **{word: float("nan") for word in (".nan", ".NaN", ".NAN")},
}
_SURROGATE = re.compile("[\ud800-\udfff]")
_FLOW_TOKEN = re.compile(r"\"(?:[^\"\\]|\\.)*\"|'(?:[^']|'')*'|[\[\]{}]")


def check_flow_depth(text: str, file: str) -> None:
    """Refuse flow collections nested deeper than :data:`MAX_DEPTH` before ruamel scans them
    (its scanner is quadratic in the flow depth). Quoted strings are skipped."""
    check_bracket_depth(text, file, MAX_DEPTH, _FLOW_TOKEN, "values")


@dataclass
class _Anchor:
    value: Any
    size: int
    values: list[tuple[PathKey, Location]]
    keys: list[tuple[PathKey, Location]]


@dataclass
class _Open:
    """A collection being built: its value, path, anchor and (for mappings) the pending key."""

    value: dict[str, Any] | list[Any]
    path: PathKey
    anchor: str | None
    start_nodes: int
    start_values: int
    start_keys: int
    key: str | None = None
    seen: dict[str, Location] = field(default_factory=dict)


class EventBuilder:
    """Consume the events of one document into plain values, filling ``values``/``keys`` locations."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.values: list[tuple[PathKey, Location]] = []
        self.keys: list[tuple[PathKey, Location]] = []
        self.nodes = 0
        self.alias_nodes = 0
        self.anchors: dict[str, _Anchor] = {}
        self.open_anchors: set[str] = set()

    def loc(self, event: ev.Event) -> Location:
        mark = event.start_mark
        return Location(self.file, mark.line + 1, mark.column + 1)

    def build(self, stream: Iterator[ev.Event]) -> tuple[bool, Any]:
        """Values of the stream's single document: ``(False, None)`` for an empty stream."""
        documents = 0
        result: Any = None
        for event in stream:
            if isinstance(event, ev.DocumentStartEvent):
                documents += 1
                if documents > 1:
                    raise RGraphError.at(self.loc(event), "expected a single YAML document, found a second one")
                self._directives(event)
                result = self._document(stream)
        return documents > 0, result

    def _directives(self, event: ev.DocumentStartEvent) -> None:
        version = getattr(event, "version", None)
        if version is not None and tuple(version) != (1, 2):
            shown = ".".join(str(v) for v in version)
            raise RGraphError.at(self.loc(event), f"'%YAML {shown}' is not supported: rgraph reads YAML 1.2 only")
        if getattr(event, "tags", None):
            raise RGraphError.at(self.loc(event), "'%TAG' directives are not allowed (plain values only)")

    def _document(self, stream: Iterator[ev.Event]) -> Any:
        stack: list[_Open] = []
        root: Any = None
        for event in stream:
            if isinstance(event, ev.DocumentEndEvent):
                return root
            if isinstance(event, ev.CollectionEndEvent):
                done = stack.pop()
                self._close(done)
                value: Any = done.value
            else:
                parent = stack[-1] if stack else None
                if parent is not None and isinstance(parent.value, dict) and parent.key is None:
                    self._key(parent, event)
                    continue
                path = self._child_path(parent)
                if isinstance(event, ev.CollectionStartEvent):
                    if len(stack) >= MAX_DEPTH:
                        raise RGraphError.at(self.loc(event), f"values nested deeper than {MAX_DEPTH} levels")
                    stack.append(self._open(event, path))
                    continue
                value = self._leaf(event, path)
            if not stack:
                root = value
                continue
            parent = stack[-1]
            if isinstance(parent.value, dict):
                assert parent.key is not None
                parent.value[parent.key] = value
                parent.key = None
            else:
                parent.value.append(value)
        raise RGraphError.in_file(self.file, "unexpected end of the YAML stream")

    def _child_path(self, parent: _Open | None) -> PathKey:
        if parent is None:
            return ()
        if isinstance(parent.value, dict):
            return (*parent.path, parent.key)  # type: ignore[arg-type]
        return (*parent.path, len(parent.value))

    def _count(self, event: ev.Event, n: int = 1) -> None:
        self.nodes += n
        if self.nodes > MAX_NODES:
            raise RGraphError.at(self.loc(event), f"document too large (more than {MAX_NODES:,} values)")

    def _no_tag(self, event: ev.NodeEvent) -> None:
        tag = getattr(event, "tag", None)
        if tag is None:
            return
        shown = "!!" + tag[len("tag:yaml.org,2002:"):] if tag.startswith("tag:yaml.org,2002:") else tag
        raise RGraphError.at(self.loc(event), f"YAML tag {quote(shown)} is not allowed (plain values only)")

    def _open(self, event: ev.CollectionStartEvent, path: PathKey) -> _Open:
        self._no_tag(event)
        self._count(event)
        self.values.append((path, self.loc(event)))
        anchor = event.anchor
        if anchor is not None:
            self.open_anchors.add(anchor)
        value: dict[str, Any] | list[Any] = {} if isinstance(event, ev.MappingStartEvent) else []
        return _Open(value, path, anchor, self.nodes - 1, len(self.values) - 1, len(self.keys))

    def _close(self, done: _Open) -> None:
        if done.anchor is None:
            return
        self.open_anchors.discard(done.anchor)
        n = len(done.path)
        self.anchors[done.anchor] = _Anchor(
            done.value, self.nodes - done.start_nodes,
            [(p[n:], loc) for p, loc in self.values[done.start_values:]],
            [(p[n:], loc) for p, loc in self.keys[done.start_keys:]],
        )

    def _key(self, parent: _Open, event: ev.Event) -> None:
        loc = self.loc(event)
        if not isinstance(event, ev.ScalarEvent):
            raise RGraphError.at(loc, "mapping keys must be plain strings")
        self._no_tag(event)
        if event.anchor is not None:
            raise RGraphError.at(loc, "anchors on mapping keys are not supported")
        if event.value == "<<" and event.style is None:
            raise RGraphError.at(loc, "YAML merge keys ('<<') are not supported")
        self._count(event)
        key = event.value
        check_text(key, loc)
        if key in parent.seen:
            first = parent.seen[key]
            raise RGraphError.at(loc, f"duplicate key {quote(key)} (first defined at line {first.line})")
        if len(parent.seen) >= MAX_KEYS:
            raise RGraphError.at(loc, f"more than {MAX_KEYS:,} keys in one mapping")
        parent.seen[key] = loc
        parent.key = key
        self.keys.append(((*parent.path, key), loc))

    def _leaf(self, event: ev.Event, path: PathKey) -> Any:
        loc = self.loc(event)
        if isinstance(event, ev.AliasEvent):
            return self._alias(event, path, loc)
        assert isinstance(event, ev.ScalarEvent), type(event)
        self._no_tag(event)
        self._count(event)
        self.values.append((path, loc))
        value = scalar_value(event.value, event.style, loc)
        if event.anchor is not None:
            self.anchors[event.anchor] = _Anchor(value, 1, [((), loc)], [])
        return value

    def _alias(self, event: ev.AliasEvent, path: PathKey, loc: Location) -> Any:
        name = event.anchor
        if name in self.open_anchors:
            raise RGraphError.at(loc, f"recursive alias '*{name}' (it refers to the value that contains it)")
        anchor = self.anchors.get(name)
        if anchor is None:
            raise RGraphError.at(loc, f"undefined alias '*{name}'")
        self.alias_nodes += anchor.size
        if self.alias_nodes > MAX_ALIAS_NODES:
            raise RGraphError.at(loc, f"aliases expand to more than {MAX_ALIAS_NODES:,} values")
        self._count(event, anchor.size)
        self.values.extend(((*path, *sub), at) for sub, at in anchor.values)
        self.keys.extend(((*path, *sub), at) for sub, at in anchor.keys)
        return anchor.value


def check_text(text: str, loc: Location) -> None:
    """Refuse lone surrogates and control characters (other than tab and newline) in any text."""
    if _SURROGATE.search(text):
        raise RGraphError.at(loc, f"text {quote(text)} contains a lone surrogate (not valid Unicode text)")
    bad = CONTROL.search(text)
    if bad:
        raise RGraphError.at(loc, f"text {quote(text)} contains the control character U+{ord(bad.group()):04X}")


def scalar_value(text: str, style: str | None, loc: Location) -> Any:
    """The core-schema value of one scalar: quoted and block scalars are strings."""
    if style == ">":  # ruamel's round-trip scanner marks fold points with BEL (raw BELs never get here)
        text = text.replace("\a", "")
    check_text(text, loc)
    if style is not None:
        return text
    if text in _NULL:
        return None
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    if not text or text[0] not in "-+0123456789.":
        return text
    cleaned = text.replace("_", "") if "_" in text else text
    if _DEC.fullmatch(cleaned):
        return _checked_int(cleaned, 10, loc)
    if _HEX.fullmatch(cleaned):
        return _checked_int(cleaned[2:], 16, loc)
    if _OCT.fullmatch(cleaned):
        return _checked_int(cleaned[2:], 8, loc)
    if _FLOAT.fullmatch(cleaned):
        return float(cleaned)
    return _SPECIAL_FLOAT.get(text, text)


def _checked_int(digits: str, base: int, loc: Location) -> int:
    sign = -1 if digits[0] == "-" else 1
    body = digits.lstrip("+-").lstrip("0") or "0"
    if len(body) * {10: 3.33, 16: 4, 8: 3}[base] > MAX_INT_BITS + 4:
        raise RGraphError.at(loc, f"integer out of range ({len(body)} digits; at most {MAX_INT_BITS} bits)")
    value = sign * int(body, base)
    if value.bit_length() > MAX_INT_BITS:
        raise RGraphError.at(loc, f"integer out of range (at most {MAX_INT_BITS} bits)")
    return value
