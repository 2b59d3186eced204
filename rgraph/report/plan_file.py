"""Read a plan JSON file (docs/plan.md) and check the shape the views rely on.

Bad files raise ``RGraphError``: decode errors carry the JSON line and column; shape
errors name the JSON path of the offending value and, when the text is at hand, its line
and column.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rgraph.errors import RGraphError
from rgraph.jsonloc import locate, path_parts
from rgraph.plan.model import PLAN_FORMAT

Plan = dict[str, Any]


def load_plan(path: str | Path) -> Plan:
    """The plan dict in ``path``; ``RGraphError`` for a missing, undecodable or malformed file."""
    from rgraph.check import load_plan_file

    plan, text = load_plan_file(path)
    check_plan(plan, str(path), text)
    return plan


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


class _Checker:
    def __init__(self, file: str, text: str | None) -> None:
        self.file = file
        self.text = text

    def fail(self, where: str, message: str) -> RGraphError:
        line, col = locate(self.text, path_parts(where)) if self.text is not None else (1, 1)
        return RGraphError.in_file(self.file, f"malformed plan: {where}: {message}", line, col)

    def typed(self, value: Any, where: str, kinds: tuple[type, ...], what: str) -> Any:
        ok = isinstance(value, kinds) and not (isinstance(value, bool) and bool not in kinds)
        if not ok:
            raise self.fail(where, f"expected {what}, got {json.dumps(value)[:60]}")
        return value

    def obj(self, value: Any, where: str) -> dict[str, Any]:
        return self.typed(value, where, (dict,), "an object")

    def items(self, parent: dict[str, Any], key: str, where: str, required: bool = False) -> list[Any]:
        if key not in parent or parent[key] is None:
            if required:
                raise self.fail(where or "top level", f"missing key {key!r}")
            return []
        return self.typed(parent[key], _join(where, key), (list,), "a list")

    def field(self, parent: dict[str, Any], key: str, where: str, kinds: tuple[type, ...], what: str,
              required: bool = True) -> Any:
        if key not in parent:
            if required:
                raise self.fail(where, f"missing key {key!r}")
            return None
        return self.typed(parent[key], _join(where, key), kinds, what)

    def each(self, parent: dict[str, Any], key: str, where: str, check: Callable[[dict[str, Any], str], None],
             required: bool = False) -> None:
        for i, item in enumerate(self.items(parent, key, where, required)):
            at = f"{_join(where, key)}[{i}]"
            check(self.obj(item, at), at)


def check_plan(plan: Any, file: str, text: str | None = None) -> None:
    """Raise ``RGraphError`` unless ``plan`` has the keys and types the views read.

    ``text`` is the JSON ``plan`` was read from, to locate the offending value.
    """
    c = _Checker(file, text)
    if not isinstance(plan, dict):
        raise c.fail("top level", "expected an object")
    fmt = plan.get("format")
    if fmt != PLAN_FORMAT:
        raise c.fail("format", f"expected {PLAN_FORMAT!r}, got {json.dumps(fmt)}")
    str_ = (str,)
    opt_str = (str, type(None))
    opt_int = (int, type(None))
    rng = (list, type(None))

    def sub(parent: dict[str, Any], at: str) -> None:
        value = parent.get("subresource")
        if value is None:
            return
        c.obj(value, f"{at}.subresource")
        for key in ("mips", "layers"):
            r = value.get(key)
            if r is None:
                continue
            ok = isinstance(r, list) and len(r) == 2 and all(isinstance(x, int) for x in r)
            if not ok or r[0] > r[1]:
                raise c.fail(f"{at}.subresource.{key}", "expected a half-open range [begin, end]")

    def flag_list(parent: dict[str, Any], key: str, at: str) -> None:
        for i, name in enumerate(c.items(parent, key, at)):
            c.typed(name, f"{at}.{key}[{i}]", str_, "a string")

    def state(parent: dict[str, Any], key: str, at: str) -> None:
        value = c.obj(parent.get(key), f"{at}.{key}")
        flag_list(value, "stages", f"{at}.{key}")
        flag_list(value, "access", f"{at}.{key}")
        c.field(value, "layout", f"{at}.{key}", opt_str, "a layout name or null", required=False)
        c.field(value, "queue", f"{at}.{key}", opt_str, "a queue name", required=False)

    def access(a: dict[str, Any], at: str) -> None:
        c.field(a, "resource", at, str_, "a resource name")
        c.field(a, "usage", at, opt_str, "a usage name", required=False)
        c.field(a, "write", at, (bool, type(None)), "true or false", required=False)
        flag_list(a, "stages", at)
        flag_list(a, "access", at)
        sub(a, at)

    def barrier(b: dict[str, Any], at: str) -> None:
        c.field(b, "resource", at, str_, "a resource name")
        aliases = c.field(b, "aliases", at, (str, list, type(None)), "resource name(s) or null", required=False)
        if isinstance(aliases, list):
            for i, name in enumerate(aliases):
                c.typed(name, f"{at}.aliases[{i}]", str_, "a resource name")
        sub(b, at)
        state(b, "src", at)
        state(b, "dst", at)

    def semaphore(s: dict[str, Any], at: str) -> None:
        c.field(s, "queue", at, str_, "a queue name")
        c.field(s, "value", at, (int,), "an integer")
        flag_list(s, "stages", at)

    def pass_(p: dict[str, Any], at: str) -> None:
        c.field(p, "name", at, str_, "a pass name")
        c.field(p, "index", at, (int,), "an integer", required=False)
        c.field(p, "kind", at, opt_str, "a pass kind", required=False)
        c.field(p, "queue", at, opt_str, "a queue name", required=False)
        c.field(p, "impl", at, opt_str, "an implementation name or null", required=False)
        c.each(p, "accesses", at, access)
        c.each(p, "barriers", at, barrier)
        c.each(p, "releases", at, barrier)
        c.each(p, "waits", at, semaphore)
        c.each(p, "signals", at, semaphore)

    def resource(r: dict[str, Any], at: str) -> None:
        c.field(r, "name", at, str_, "a resource name")
        for key in ("bytes", "alignment", "first", "last", "heap", "offset", "size_bytes"):
            c.field(r, key, at, opt_int, "an integer or null", required=False)
        c.field(r, "extent", at, rng, "a list of integers", required=False)

    def heap(h: dict[str, Any], at: str) -> None:
        c.field(h, "id", at, (int,), "an integer")
        c.field(h, "bytes", at, (int,), "an integer")
        c.field(h, "memory_class", at, opt_str, "a memory class", required=False)

    def culled(entry: dict[str, Any], at: str) -> None:
        c.field(entry, "pass", at, str_, "a pass name")
        c.field(entry, "reason", at, opt_str, "a reason", required=False)
        c.field(entry, "bytes", at, opt_int, "an integer", required=False)
        for i, name in enumerate(c.items(entry, "resources", at)):
            c.typed(name, f"{at}.resources[{i}]", str_, "a resource name")

    def dropped(entry: dict[str, Any], at: str) -> None:
        c.field(entry, "pass", at, str_, "a pass name")
        c.field(entry, "resource", at, str_, "a resource name")

    c.each(plan, "passes", "", pass_, required=True)
    c.each(plan, "resources", "", resource)
    c.each(plan, "heaps", "", heap)
    c.each(plan, "culled", "", culled)
    c.each(plan, "dropped_reads", "", dropped)
    if plan.get("stats") is not None:
        stats = c.obj(plan["stats"], "stats")
        for key, value in stats.items():
            if key != "policy":
                c.typed(value, f"stats.{key}", (int, float, type(None)), "a number")
