"""Knob parsing and the settings a sweep renders.

A knob is a graph param with a list of values (``--knob hbao.directions=2,4,8``). By
default each knob moves alone from the defaults; ``grid`` takes every combination. The
reference setting is the defaults overridden by every ``--reference name=value``.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rgraph.errors import RGraphError
from rgraph.spec.loader import GraphSource
from rgraph.spec.specialize import resolve_params

MAX_SETTINGS = 1024
_UNSAFE = re.compile(r"[^A-Za-z0-9._=+-]+")


@dataclass(frozen=True)
class Knob:
    name: str
    values: tuple[str, ...]  # as given on the command line


@dataclass(frozen=True)
class Setting:
    """One rendering of the graph: the ``-p`` overrides it runs with and what it varies."""

    label: str  # "reference", "default", "hbao.directions=4" or "a=1,b=2" (grid)
    role: str  # "reference" | "default" | "knob"
    overrides: dict[str, str]  # every -p override, base ones included
    varied: dict[str, str] = field(default_factory=dict)  # knob name -> value text this setting sets

    @property
    def slug(self) -> str:
        """A file-name-safe form of the label."""
        return _UNSAFE.sub("_", self.label.replace(",", "_"))


def _cli_error(message: str) -> RGraphError:
    return RGraphError.in_file("<command line>", message)


def parse_knob(text: str) -> Knob:
    name, sep, values = text.partition("=")
    items = tuple(v.strip() for v in values.split(","))
    if not sep or not name.strip() or not values.strip() or any(not v for v in items):
        raise _cli_error(f"--knob expects name=v1,v2,..., got '{text}'")
    if len(set(items)) != len(items):
        raise _cli_error(f"--knob {name.strip()}: a value is listed twice in '{values}'")
    return Knob(name.strip(), items)


def parse_assignments(items: Sequence[str] | None, option: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise _cli_error(f"{option} expects name=value, got '{item}'")
        if name.strip() in out:
            raise _cli_error(f"{option} {name.strip()} is given twice")
        out[name.strip()] = value.strip()
    return out


def numeric_key(text: str) -> tuple[int, float, str]:
    """Sort key: numbers by value first, then other text as written."""
    try:
        return (0, float(text), "")
    except ValueError:
        return (1, 0.0, text)


def resolved(source: GraphSource, overrides: Mapping[str, str]) -> dict[str, Any]:
    """The graph's params with ``overrides`` applied (typed; bad names or values raise)."""
    return resolve_params(source, overrides)


def expand(
    source: GraphSource,
    knobs: Sequence[Knob],
    *,
    base: Mapping[str, str] | None = None,
    reference: Mapping[str, str] | None = None,
    grid: bool = False,
) -> list[Setting]:
    """Reference first, then the defaults, then every knob setting. Settings with equal
    resolved params may repeat (a knob value equal to its default); the runner renders
    each distinct one once."""
    base = dict(base or {})
    if not knobs:
        raise _cli_error("sweep needs at least one --knob name=v1,v2,...")
    names = [k.name for k in knobs]
    for name in names:
        if names.count(name) > 1:
            raise _cli_error(f"--knob {name} is given twice")
        if name in base:
            raise _cli_error(f"'{name}' is both a --knob and a -p override")
    settings = [Setting("reference", "reference", {**base, **(reference or {})}),
                Setting("default", "default", dict(base))]
    if grid:
        count = 1
        for k in knobs:
            count *= len(k.values)
        if count > MAX_SETTINGS:
            raise _cli_error(f"--grid gives {count} settings (at most {MAX_SETTINGS})")
        for combo in itertools.product(*(k.values for k in knobs)):
            varied = dict(zip(names, combo, strict=True))
            label = ",".join(f"{n}={v}" for n, v in varied.items())
            settings.append(Setting(label, "knob", {**base, **varied}, varied))
    else:
        for knob in knobs:
            for value in knob.values:
                settings.append(Setting(f"{knob.name}={value}", "knob", {**base, knob.name: value},
                                        {knob.name: value}))
    for s in settings:  # bad names or values fail here, before any rendering
        resolved(source, s.overrides)
    return settings


def params_key(params: Mapping[str, Any]) -> tuple:
    """A hashable identity of resolved params (runs with equal keys render the same)."""
    return tuple(sorted((k, repr(v)) for k, v in params.items()))
