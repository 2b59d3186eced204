"""JSON -> plan model, checking shape (keys, types, bounds) and consistency (references).

Every problem raises ``RGraphError`` with one line
``FILE:LINE:COL: error: malformed plan: JSON.PATH: what is wrong``; the line and column
are those of the offending value when the JSON text is at hand.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any, NoReturn

from rgraph.errors import RGraphError
from rgraph.jsonloc import locate, path_parts
from rgraph.plan.model import (
    IMAGE_KEYS,
    LIFETIMES,
    OPTIONAL_TOP_KEYS,
    PLAN_FORMAT,
    QUEUE_ORDER,
    RESOURCE_KINDS,
    Access,
    Barrier,
    CellState,
    Culled,
    DroppedRead,
    EndState,
    Heap,
    Plan,
    PlanPass,
    PlanResource,
    Signal,
    State,
    Stats,
    Subresource,
    Wait,
)

MAX_SIZE = 2**63 - 1  # bytes, offsets, alignments: a VkDeviceSize that fits a signed 64-bit int
MAX_COUNT = 2**31 - 1  # indices, mips, layers, extents, semaphore values
MAX_PARAM_DEPTH = 4
_FLAG = re.compile(r"[A-Z][A-Z0-9_]*\Z")

Where = str


class _Shape(Exception):
    def __init__(self, where: Where, message: str) -> None:
        super().__init__(f"{where}: {message}")
        self.where = where
        self.message = message


def _fail(where: Where, message: str) -> NoReturn:
    raise _Shape(where or "top level", message)


def _join(where: Where, key: str | int) -> Where:
    if isinstance(key, int):
        return f"{where}[{key}]"
    return f"{where}.{key}" if where else key


def _show(value: Any) -> str:
    try:
        return json.dumps(value)[:60]
    except (TypeError, ValueError):
        return type(value).__name__


def _expect(ok: bool, value: Any, where: Where, what: str) -> None:
    if not ok:
        _fail(where, f"expected {what}, got {_show(value)}")


# -- scalars -----------------------------------------------------------------------------

def _int(value: Any, where: Where, lo: int = 0, hi: int = MAX_COUNT) -> int:
    _expect(type(value) is int, value, where, "an integer")
    if not lo <= value <= hi:
        _fail(where, f"expected an integer in [{lo}, {hi}], got {_show(value)}")
    return value


def _size(value: Any, where: Where) -> int:
    return _int(value, where, 0, MAX_SIZE)


def _opt_int(value: Any, where: Where) -> int | None:
    return None if value is None else _int(value, where)


def _str(value: Any, where: Where) -> str:
    _expect(isinstance(value, str) and value != "", value, where, "a non-empty string")
    return value


def _opt_str(value: Any, where: Where) -> str | None:
    return None if value is None else _str(value, where)


def _bool(value: Any, where: Where) -> bool:
    _expect(isinstance(value, bool), value, where, "true or false")
    return value


def _flag(value: Any, where: Where) -> str:
    _expect(isinstance(value, str) and _FLAG.match(value) is not None, value, where,
            "an upper-case Vulkan name (e.g. COMPUTE_SHADER)")
    return value


def _opt_flag(value: Any, where: Where) -> str | None:
    return None if value is None else _flag(value, where)


def _one_of(choices: tuple[str, ...]) -> Callable[[Any, Where], str]:
    def check(value: Any, where: Where) -> str:
        _expect(value in choices, value, where, "one of " + ", ".join(choices))
        return value
    return check


_queue = _one_of(QUEUE_ORDER)


def _opt_queue(value: Any, where: Where) -> str | None:
    return None if value is None else _queue(value, where)


def _list(value: Any, where: Where, item: Callable[[Any, Where], Any]) -> tuple:
    _expect(isinstance(value, list), value, where, "a list")
    return tuple(item(v, _join(where, i)) for i, v in enumerate(value))


def _flags(value: Any, where: Where) -> tuple[str, ...]:
    return _list(value, where, _flag)


def _names(value: Any, where: Where) -> tuple[str, ...]:
    return _list(value, where, _str)


def _param_value(value: Any, where: Where, depth: int = 0) -> Any:
    if value is None or isinstance(value, bool | str | float):
        return value
    if isinstance(value, int):
        return _int(value, where, -MAX_SIZE - 1, MAX_SIZE)
    if depth < MAX_PARAM_DEPTH and isinstance(value, list):
        return tuple(_param_value(v, _join(where, i), depth + 1) for i, v in enumerate(value))
    if depth < MAX_PARAM_DEPTH and isinstance(value, dict):
        return _mapping(value, where, depth + 1)
    _fail(where, f"expected a number, string, boolean, null or a shallow list/object, got {_show(value)}")


def _mapping(value: Any, where: Where, depth: int = 0) -> Mapping[str, Any]:
    _expect(isinstance(value, dict), value, where, "an object")
    return MappingProxyType({k: _param_value(v, _join(where, k), depth) for k, v in sorted(value.items())})


# -- objects -----------------------------------------------------------------------------

class _Obj:
    """One JSON object being read: typed field access and a check for unknown keys."""

    def __init__(self, value: Any, where: Where, known: tuple[str, ...]) -> None:
        _expect(isinstance(value, dict), value, where, "an object")
        self.d: dict[str, Any] = value
        self.where = where
        for key in value:
            if key not in known:
                _fail(_join(where, key), f"unknown key {key!r} (expected one of {', '.join(known)})")

    def __call__(self, key: str, conv: Callable[[Any, Where], Any], default: Any = ..., **kw: Any) -> Any:
        if key not in self.d:
            if default is ...:
                _fail(self.where, f"missing key {key!r}")
            return default
        return conv(self.d[key], _join(self.where, key), **kw)


def _range(value: Any, where: Where) -> tuple[int, int]:
    ok = isinstance(value, list) and len(value) == 2 and all(type(x) is int for x in value)
    if not ok or not 0 <= value[0] < value[1] <= MAX_COUNT:
        _fail(where, "expected a half-open range [begin, end]")
    return (value[0], value[1])


def _subresource(value: Any, where: Where) -> Subresource | None:
    if value is None:
        return None
    o = _Obj(value, where, ("mips", "layers"))
    return Subresource(o("mips", _range), o("layers", _range))


_STATE_KEYS = ("stages", "access", "layout", "queue")


def _state_of(o: _Obj) -> State:
    return State(o("stages", _flags), o("access", _flags), o("layout", _opt_flag), o("queue", _opt_queue))


def _state(value: Any, where: Where) -> State:
    return _state_of(_Obj(value, where, _STATE_KEYS))


def _end_state(value: Any, where: Where) -> EndState:
    if value is None:
        return None
    if isinstance(value, list):
        def cell(v: Any, at: Where) -> CellState:
            o = _Obj(v, at, ("subresource", *_STATE_KEYS))
            sub = o("subresource", _subresource)
            if sub is None:
                _fail(_join(at, "subresource"), "expected an object, got null")
            return CellState(sub, _state_of(o))
        return _list(value, where, cell)
    return _state(value, where)


def _aliases(value: Any, where: Where) -> tuple[str, ...]:
    if value is None:
        return ()
    if isinstance(value, str):
        return (_str(value, where),)
    _expect(isinstance(value, list), value, where, "resource name(s) or null")
    return _names(value, where)


def _access(value: Any, where: Where) -> Access:
    o = _Obj(value, where, ("resource", "subresource", "usage", "stages", "access", "layout", "write"))
    return Access(o("resource", _str), o("subresource", _subresource), o("usage", _str), o("stages", _flags),
                  o("access", _flags), o("layout", _opt_flag), o("write", _bool))


def _barrier(value: Any, where: Where) -> Barrier:
    o = _Obj(value, where, ("resource", "subresource", "src", "dst", "aliases"))
    return Barrier(o("resource", _str), o("subresource", _subresource), o("src", _state), o("dst", _state),
                   o("aliases", _aliases))


def _semaphore(cls: type) -> Callable[[Any, Where], Any]:
    def read(value: Any, where: Where) -> Any:
        o = _Obj(value, where, ("queue", "value", "stages", "device"))
        return cls(o("queue", _queue), o("value", _int, lo=1), o("stages", _flags), o("device", _int, None))
    return read


def _pass(value: Any, where: Where) -> PlanPass:
    o = _Obj(value, where, ("name", "index", "device", "queue", "kind", "impl", "params", "accesses", "barriers",
                            "releases", "waits", "signals"))
    return PlanPass(
        name=o("name", _str), index=o("index", _int), device=o("device", _int), queue=o("queue", _queue),
        kind=o("kind", _str), impl=o("impl", _opt_str), params=o("params", _mapping),
        accesses=o("accesses", _list, item=_access), barriers=o("barriers", _list, item=_barrier),
        releases=o("releases", _list, item=_barrier), waits=o("waits", _list, item=_semaphore(Wait)),
        signals=o("signals", _list, item=_semaphore(Signal)),
    )


def _extent(value: Any, where: Where) -> tuple[int, int, int] | None:
    if value is None:
        return None
    ext = _list(value, where, lambda v, at: _int(v, at, 1))
    if len(ext) != 3:
        _fail(where, f"expected [width, height, depth], got {_show(value)}")
    return ext


def _resource(value: Any, where: Where) -> PlanResource:
    o = _Obj(value, where, ("name", "kind", "format", "bytes", "size_bytes", "alignment", "memory_type_bits",
                            "memory_class", "usages", "lifetime", "first", "last", "heap", "offset", "initial",
                            "final", "extent", "mips", "layers", "samples", "accel", "scratch_of", "device"))
    extent = o("extent", _extent, None)
    kind = o("kind", _one_of(RESOURCE_KINDS))
    if kind == "image" and extent is None:
        _fail(_join(where, "extent"), "an image needs an extent [width, height, depth]")
    counts = {key: o(key, _opt_int, None) if kind != "image" else o(key, _int, lo=1) for key in IMAGE_KEYS[1:]}
    heap, offset = o("heap", _opt_int), o("offset", lambda v, at: None if v is None else _size(v, at))
    if (heap is None) != (offset is None):
        _fail(_join(where, "offset"), "heap and offset are both set or both null")
    return PlanResource(
        name=o("name", _str), kind=kind, format=o("format", _opt_flag),
        bytes=o("bytes", _size), size_bytes=o("size_bytes", lambda v, at: None if v is None else _size(v, at)),
        alignment=o("alignment", _int, lo=1, hi=MAX_SIZE), memory_type_bits=o("memory_type_bits", _int, hi=2**32 - 1),
        memory_class=o("memory_class", _str), usages=o("usages", _names), lifetime=o("lifetime", _one_of(LIFETIMES)),
        first=o("first", _opt_int), last=o("last", _opt_int), heap=heap, offset=offset,
        initial=o("initial", _end_state), final=o("final", _end_state), extent=extent, **counts,
        accel=o("accel", _accel, None), scratch_of=o("scratch_of", _opt_str, None),
        absent=_image_keys_absent(o.d, extent), device=o("device", _int, 0),
    )


def _accel(value: Any, where: Where) -> Mapping[str, Any]:
    """An accel's layout, read-only and in file order (the compiler writes it)."""
    def frozen(v: Any, at: Where) -> Any:
        if isinstance(v, dict):
            return MappingProxyType({k: frozen(x, _join(at, k)) for k, x in v.items()})
        if isinstance(v, list):
            return tuple(frozen(x, _join(at, i)) for i, x in enumerate(v))
        return _param_value(v, at)

    _expect(isinstance(value, dict), value, where, "an object")
    return frozen(value, where)


def _image_keys_absent(d: Mapping[str, Any], extent: Any) -> frozenset[str] | None:
    """None when the image-only keys are present exactly as compile writes them."""
    absent = frozenset(k for k in IMAGE_KEYS if k not in d)
    canonical = frozenset() if extent is not None else frozenset(IMAGE_KEYS)
    return None if absent == canonical else absent


def _heap(value: Any, where: Where) -> Heap:
    o = _Obj(value, where, ("id", "bytes", "memory_class", "alignment", "device"))
    return Heap(o("id", _int), o("bytes", _size), o("memory_class", _str), o("alignment", _int, lo=1, hi=MAX_SIZE),
                o("device", _int, 0))


def _culled(value: Any, where: Where) -> Culled:
    o = _Obj(value, where, ("pass", "reason", "resources", "bytes"))
    return Culled(o("pass", _str), o("reason", _str), o("resources", _names), o("bytes", _size))


def _dropped(value: Any, where: Where) -> DroppedRead:
    o = _Obj(value, where, ("pass", "resource", "reason"))
    return DroppedRead(o("pass", _str), o("resource", _str), o("reason", _str))


def _stats(value: Any, where: Where) -> Stats:
    o = _Obj(value, where, ("barriers", "semaphores", "peak_bytes", "lower_bound_bytes", "unaliased_bytes",
                            "allocations", "policy", "sync", "schedule"))
    count = _int
    return Stats(o("barriers", count, None), o("semaphores", count, None), o("peak_bytes", _size, None),
                 o("lower_bound_bytes", _size, None), o("unaliased_bytes", _size, None),
                 o("allocations", count, None), o("policy", _str, None), o("sync", _str, None),
                 o("schedule", _str, None))


def _format(value: Any, where: Where) -> str:
    if value != PLAN_FORMAT:
        _fail(where, f"expected {PLAN_FORMAT!r}, got {_show(value)}")
    return value


def _plan(doc: Any) -> Plan:
    o = _Obj(doc, "", ("format", "graph", "source", "scene", "scene_source", "size", "params", "features",
                       "device_profile", "queues", "passes", "culled", "dropped_reads", "resources", "heaps",
                       "outputs", "stats", "camera", "multi_device"))
    fmt = o("format", _format)
    passes = o("passes", _list, item=_pass)
    resources = o("resources", _list, item=_resource)
    size = o("size", _list, item=lambda v, at: _int(v, at, 1))
    if len(size) != 2:
        _fail("size", f"expected [width, height], got {_show(doc['size'])}")
    plan = Plan(
        format=fmt, graph=o("graph", _str), source=o("source", _opt_str), scene=o("scene", _opt_str),
        scene_source=o("scene_source", _opt_str, None), size=size, params=o("params", _mapping),
        features=o("features", _mapping, MappingProxyType({})), device_profile=o("device_profile", _str),
        queues=o("queues", _list, item=_queue), passes=passes, resources=resources,
        culled=o("culled", _list, item=_culled), dropped_reads=o("dropped_reads", _list, item=_dropped),
        heaps=o("heaps", _list, item=_heap), outputs=o("outputs", _names, ()), stats=o("stats", _stats),
        camera=o("camera", lambda v, at: _int(v, at, 0), 0),
        multi_device=o("multi_device", _mapping, None),
        absent=frozenset(k for k in OPTIONAL_TOP_KEYS if k not in doc),
    )
    from rgraph.plan.consistency import check_consistency

    problem = check_consistency(plan)
    if problem is not None:
        _fail(*problem)
    return plan


# -- entry points ------------------------------------------------------------------------

def from_json_dict(doc: Any, file: str = "<plan>", text: str | None = None) -> Plan:
    """The plan model of a decoded plan document; ``text`` (its JSON) locates errors."""
    try:
        return _plan(doc)
    except _Shape as exc:
        line, col = locate(text, path_parts(exc.where)) if text is not None else (1, 1)
        raise RGraphError.in_file(file, f"malformed plan: {exc.where}: {exc.message}", line, col) from None


def parse(text: str, file: str = "<plan>") -> Plan:
    """The plan in JSON ``text``; ``RGraphError`` (located) for invalid JSON or a malformed plan."""
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RGraphError.in_file(file, f"invalid JSON: {exc.msg}", exc.lineno, exc.colno) from None
    except RecursionError:
        raise RGraphError.in_file(file, "invalid JSON: nested too deeply") from None
    except ValueError as exc:  # e.g. an integer literal longer than Python converts
        raise RGraphError.in_file(file, f"invalid JSON: {exc}") from None
    return from_json_dict(doc, file, text)


def read_text(path: str | os.PathLike[str]) -> str:
    """The text of plan file ``path``; ``RGraphError`` if it cannot be read."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RGraphError.in_file(path, "plan file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RGraphError.in_file(path, f"cannot read plan file: {exc}") from None


def load(path_or_text: str | os.PathLike[str]) -> Plan:
    """The plan in a file (a path) or in JSON text (a string starting with ``{``)."""
    if isinstance(path_or_text, str) and path_or_text.lstrip().startswith("{"):
        return parse(path_or_text)
    return parse(read_text(path_or_text), str(path_or_text))
