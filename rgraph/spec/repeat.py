"""Repeated passes (``for:``) and ``${...}`` inside names and resource keys.

A pass with ``for: {i: [first, stop]}`` stands for one pass per ``i`` in ``range(first,
stop)``, in order, at its place in the declaration order; ``first`` and ``stop`` may be
expressions over ``params.*`` and ``scene.*``. Its name and its ``reads``/``writes`` keys are
templates: each ``${...}`` in them is evaluated (with ``i`` bound) and replaced by the integer,
so ``bloom[mip=${i - 1}]`` selects the previous mip. Keys of other passes may use
``${params.*}``/``${scene.*}`` the same way (``bloom[mip=${params.levels - 1}]``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rgraph.errors import Location, RGraphError
from rgraph.spec.expr import FUNCTIONS, NAMESPACES, ExprError, parse
from rgraph.spec.loader import Located

MAX_REPEAT = 1024


def template_groups(text: str) -> list[tuple[int, int]]:
    """(start, end) of each top-level ``${...}`` in ``text`` (end exclusive); ValueError if unclosed."""
    groups = []
    i = 0
    while True:
        start = text.find("${", i)
        if start < 0:
            return groups
        depth, j = 1, start + 2
        while j < len(text) and depth:
            if text.startswith("${", j):
                depth, j = depth + 1, j + 2
                continue
            if text[j] == "{":
                depth += 1
            elif text[j] == "}":
                depth -= 1
            j += 1
        if depth:
            raise ValueError(start)
        groups.append((start, j))
        i = j


def substitute(text: str, values: Mapping[str, Any], local_names: frozenset[str], where: Location) -> str:
    """``text`` with each ``${expr}`` replaced by its integer value; errors located at ``where``."""
    try:
        groups = template_groups(text)
    except ValueError as exc:
        raise RGraphError.at(where, f"unclosed '${{' at offset {exc.args[0]} in '{text}'") from None
    out, last = [], 0
    for start, end in groups:
        inner = text[start + 2:end - 1]
        try:
            value = parse(inner, local_names).evaluate(values)
        except ExprError as exc:
            raise RGraphError.at(where, f"in '{text}', '${{{inner}}}': {exc.message}") from None
        if isinstance(value, float):
            if not value.is_integer():
                raise RGraphError.at(where, f"in '{text}', '${{{inner}}}' is {value}, not an integer")
            value = int(value)
        out += [text[last:start], str(value)]
        last = end
    return "".join(out) + text[last:]


def loop_variable(located: Located) -> tuple[str, list[Any]] | None:
    """The ``for:`` variable and its ``[first, stop]`` bounds (unevaluated), or None."""
    spec = located.model.for_
    if spec is None:
        return None
    where = located.loc("for")
    if len(spec) != 1:
        raise RGraphError.at(where, f"'for' takes exactly one variable, e.g. {{i: [0, 4]}}; got {len(spec)}")
    (var, bounds), = spec.items()
    if not var.isidentifier() or var in NAMESPACES or var in FUNCTIONS:
        raise RGraphError.at(located.key_loc("for", var), f"'{var}' cannot be a loop variable (use a plain name such as i)")
    if len(bounds) != 2:
        raise RGraphError.at(located.loc("for", var),
                             f"'for: {{{var}: ...}}' takes [first, stop] (half-open), got {len(bounds)} values")
    return var, bounds


def instances(name: str, located: Located, env: Any) -> list[tuple[str, dict[str, int]]]:
    """(pass name, loop bindings) for each instance of a pass; one with no bindings without ``for``."""
    loop = loop_variable(located)
    if loop is None:
        if "${" in name:
            return [(substitute(name, env.values, frozenset(), located.key_loc()), {})]
        return [(name, {})]
    var, bounds = loop
    first = env.integer(bounds[0], located, "for", var, 0)
    stop = env.integer(bounds[1], located, "for", var, 1)
    if stop - first > MAX_REPEAT:
        raise RGraphError.at(located.loc("for", var), f"'{var}' repeats {stop - first} times; the limit is {MAX_REPEAT}")
    if "${" not in name:
        raise RGraphError.at(located.key_loc(), f"repeated pass '{name}' needs '${{{var}}}' in its name, e.g. {name}_${{{var}}}")
    out = []
    for value in range(first, stop):
        values = {**env.values, var: value}
        out.append((substitute(name, values, frozenset({var}), located.key_loc()), {var: value}))
    return out
