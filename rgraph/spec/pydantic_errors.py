"""Turn pydantic validation errors into located, human messages."""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Sequence
from typing import Any, get_args

from pydantic import BaseModel, ValidationError

from rgraph.errors import Diagnostic, RGraphError, quote
from rgraph.spec.yaml_source import PathKey, SourceMap

_TYPE_NAMES = {
    "int_type": "an integer",
    "int_from_float": "an integer",
    "float_type": "a number",
    "string_type": "a string",
    "bool_type": "true or false",
    "list_type": "a list",
    "dict_type": "a mapping",
    "model_type": "a mapping",
    "model_attributes_type": "a mapping",
    "tuple_type": "a list",
}


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """``" (did you mean 'x'?)"`` when a close match exists, else ``""``."""
    if len(word) > 100:  # difflib is quadratic; nothing that long is a typo of a name
        return ""
    match = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f"; did you mean '{match[0]}'?" if match else ""


def describe(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"string {quote(value)}"
    if isinstance(value, int | float):
        return f"number {value}"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    return type(value).__name__


def _where(path: Sequence[str | int]) -> str:
    """A readable name of the place: ``pass 'hbao'``, ``resource 'depth'``, ``the graph``."""
    if len(path) >= 2 and path[0] == "passes":
        return f"pass {quote(path[1])}"
    if len(path) >= 2 and path[0] == "resources":
        return f"resource {quote(path[1])}"
    if len(path) >= 1 and isinstance(path[0], str) and path[0] not in ("passes", "resources"):
        return f"'{path[0]}'"
    return "the file"


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    """The pydantic models an annotation holds (through Optional, unions, lists, mappings)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found: list[type[BaseModel]] = []
    for arg in get_args(annotation):
        found += [m for m in _models_in(arg) if m not in found]
    return found


def _nested_fields(model: type[BaseModel], path: Sequence[str | int]) -> list[str]:
    """The field names of the model(s) at ``path``, walking field annotations; list indices and
    mapping keys (a material's name) stay on the element model."""
    current = [model]
    for part in path:
        inner = [m for c in current if isinstance(part, str) and part in c.model_fields
                 for m in _models_in(c.model_fields[part].annotation)]
        if inner:
            current = inner
    names: list[str] = []
    for m in current:
        names += [n for n in m.model_fields if n not in names]
    return names


def _model_fields(model: type[BaseModel], path: Sequence[str | int], data: Any = None) -> list[str]:
    """Best effort: the field names valid in the mapping at ``path`` for the did-you-mean."""
    from rgraph.spec import models

    if model is not models.GraphFile or not path:
        return _nested_fields(model, path)
    if path[0] == "passes" and len(path) >= 2:
        if len(path) >= 4 and path[2] in ("reads", "writes"):
            return list(models.UsageEntry.model_fields)
        return list(models.Pass.model_fields)
    if path[0] == "resources" and len(path) >= 2:
        if "scale" in path or (len(path) >= 3 and path[2] == "size"):
            return ["scale"]
        kinds = {"image": models.ImageResource, "buffer": models.BufferResource, "accel": models.AccelResource}
        entry = data.get("resources", {}).get(path[1]) if isinstance(data, dict) else None
        chosen = kinds.get(entry.get("kind")) if isinstance(entry, dict) else None
        if chosen is not None:
            return list(chosen.model_fields)
        names: set[str] = set()
        for cls in kinds.values():
            names.update(cls.model_fields)
        return sorted(names)
    return list(model.model_fields)


_FIELD_WORDS = {"requires": "scene feature", "stages": "shader stage", "kind": "pass kind", "usage": "usage"}
_BRANCHES = ("int", "str", "float", "bool", "list[union[int,str]]", "literal['output']", "ScaleSize", "light",
             "generator")


def _siblings(exc: ValidationError, loc: tuple[Any, ...]) -> list[Any]:
    """Union branch names reported for the same field as ``loc``."""
    base = loc[:-1]
    return [e["loc"][len(base)] for e in exc.errors() if e["loc"][: len(base)] == base and len(e["loc"]) > len(base)]


def _clean_loc(loc: tuple[Any, ...]) -> PathKey:
    """Drop pydantic's union/discriminator branch names from a location."""
    out: list[str | int] = []
    for part in loc:
        if isinstance(part, str) and part in _BRANCHES:
            continue
        if isinstance(part, str) and (part in ("image", "buffer", "accel") or "[" in part or part.startswith("function-")):
            if out and out[-1] != "size":
                continue
        out.append(part)
    return tuple(out)


def translate(exc: ValidationError, smap: SourceMap, model: type[BaseModel], data: Any) -> RGraphError:
    """Convert every pydantic error into a located diagnostic (deduplicated, in file order)."""
    diagnostics: list[Diagnostic] = []
    seen: set[tuple[str, str]] = set()
    for err in exc.errors():
        loc = _clean_loc(err["loc"])
        kind = err["type"]
        value = err.get("input")
        at_key = False
        if kind == "extra_forbidden":
            key = str(loc[-1])
            valid = _model_fields(model, loc[:-1] if loc else loc, data)
            if "generator" in err["loc"] or "light" in err["loc"]:  # a scene file's lights: item
                from rgraph.spec.scene import Light, LightGenerator

                valid = list((LightGenerator if "generator" in err["loc"] else Light).model_fields)
            msg = f"unknown key {quote(key)} in {_where(loc[:-1])}{did_you_mean(key, valid)} (valid keys: {', '.join(valid)})"
            at_key = True
        elif kind == "missing":
            msg = f"missing required key '{loc[-1]}' in {_where(loc[:-1])}"
            loc = loc[:-1]
            at_key = True
        elif kind == "literal_error":
            expected = err.get("ctx", {}).get("expected", "")
            choices = [c.strip().strip("'") for c in expected.replace(" or ", ", ").split(",")]
            field = str(loc[-1]) if loc and isinstance(loc[-1], str) else _field_before_index(loc)
            field = _FIELD_WORDS.get(field, field)
            shown = quote(value) if isinstance(value, str) else describe(value)
            msg = f"unknown {field} {shown}{did_you_mean(str(value), choices)} (valid: {', '.join(choices)})"
        elif kind in ("union_tag_invalid", "union_tag_not_found"):
            if kind == "union_tag_not_found":
                msg = f"missing required key 'kind' in {_where(loc)} (one of image, buffer, accel)"
                at_key = True
            else:
                tag = err.get("ctx", {}).get("tag", value)
                msg = f"unknown resource kind '{tag}'{did_you_mean(str(tag), ['image', 'buffer', 'accel'])} (valid: image, buffer, accel)"
                loc = (*loc, "kind")
        elif kind in _TYPE_NAMES:
            expected = _TYPE_NAMES[kind]
            branches = _siblings(exc, err["loc"])
            if any(p in ("int", "float") for p in err["loc"]) and "str" in branches:
                expected = "a number or a '${...}' expression" if "float" in branches else "an integer or a '${...}' expression"
            msg = f"expected {expected} for '{_field_name(loc)}', got {describe(value)}"
        elif kind == "value_error":
            msg = str(err.get("ctx", {}).get("error", err["msg"]))
        elif kind in ("too_short", "too_long"):
            msg = f"'{_field_name(loc)}': {err['msg'].lower()}"
        else:
            msg = f"'{_field_name(loc)}': {err['msg']}"
        if len(loc) == 3 and loc[0] == "resources" and loc[-1] == "size" and kind not in ("extra_forbidden", "missing"):
            msg = f"size must be 'output', [width, height] or {{scale: s}}, got {describe(value)}"
        location = smap.key(loc) if at_key else smap.value(loc)
        sig = (str(location), "")  # one message per place: union branches repeat themselves
        if sig not in seen:
            seen.add(sig)
            diagnostics.append(Diagnostic(location, msg))
    diagnostics.sort(key=lambda d: (d.location.line, d.location.col))
    return RGraphError(diagnostics)


def _field_name(loc: PathKey) -> str:
    names = [str(p) for p in loc if isinstance(p, str)]
    return names[-1] if names else "value"


def _field_before_index(loc: PathKey) -> str:
    for part in reversed(loc):
        if isinstance(part, str):
            return "usage" if part not in ("requires",) else "scene feature"
    return "value"
