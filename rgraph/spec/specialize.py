"""Specialize a loaded graph for a scene, params and output size.

Evaluates every ``${...}`` value, resolves formats and subresource selectors, checks usages
against resources, pass kinds and formats, and checks Vulkan's limits. The result, a
:class:`Spec`, holds concrete values only. Every error names file, line and column.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rgraph import formats
from rgraph.errors import Location, RGraphError, quote
from rgraph.spec.expr import ExprError, parse_value
from rgraph.spec.loader import GraphSource, Located
from rgraph.spec.models import AccelResource, ImageResource, ScaleSize
from rgraph.spec.pydantic_errors import describe, did_you_mean
from rgraph.spec.repeat import instances, substitute
from rgraph.spec.vocabulary import (
    QUEUE_PASS_KINDS,
    USAGE_PASS_KINDS,
    USAGE_RESOURCE_KINDS,
    WRITE_USAGES,
)

MAX_IMAGE_DIMENSION = 16384  # maxImageDimension2D guaranteed by common desktop GPUs
MAX_IMAGE_LAYERS = 2048
MAX_BUFFER_BYTES = 1 << 32
VALID_SAMPLES = (1, 2, 4, 8, 16, 32, 64)
MAX_SCALE = 16.0


@dataclass(frozen=True)
class Limits:
    """The device limits a graph is checked against (from a device profile when given)."""

    max_image_dimension_2d: int = MAX_IMAGE_DIMENSION
    max_image_array_layers: int = MAX_IMAGE_LAYERS
    max_buffer_bytes: int = MAX_BUFFER_BYTES


@dataclass(frozen=True, slots=True)
class ResourceSpec:
    name: str
    kind: str
    lifetime: str
    format: formats.FormatInfo | None = None
    extent: tuple[int, int, int] = (0, 0, 0)
    layers: int = 1
    mips: int = 1
    samples: int = 1
    bytes: int = 0
    loc: Location = field(default_factory=lambda: Location("?"))
    geometry: str | None = None  # accels: "scene" | "probe"
    accel: Any = None  # accels: rgraph.compiler.accel.AccelLayout once sized
    scratch_of: str | None = None  # an accel's build scratch buffer: the accel

    @property
    def is_image(self) -> bool:
        return self.kind == "image"


@dataclass(frozen=True, slots=True)
class AccessSpec:
    """One usage of one resource (range) by one pass. Slots: the compiler's walks read a few
    fields of every access (no instance dict to reach first: fewer cache lines per access)."""

    resource: str
    usage: str
    write: bool
    mips: tuple[int, int] | None  # half-open; None for buffers
    layers: tuple[int, int] | None
    stages: tuple[str, ...] | None  # explicit shader stages, else derived from the pass kind
    optional: bool
    loc: Location
    refit: bool = False  # accel_build of a persistent accel refitted each frame (reads it too)
    #: The (resource, mip, layer) cells the access touches, mip-major; a buffer has the one
    #: cell (0, 0). Computed once, at construction: every compiler phase walks them.
    cells: tuple[tuple[str, int, int], ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        mips, layers, name = self.mips, self.layers, self.resource
        if mips is None or layers is None:
            cells = ((name, 0, 0),)
        elif mips[1] - mips[0] == 1 and layers[1] - layers[0] == 1:
            cells = ((name, mips[0], layers[0]),)
        else:
            cells = tuple((name, mip, layer) for mip in range(*mips) for layer in range(*layers))
        object.__setattr__(self, "cells", cells)


@dataclass(frozen=True, slots=True)
class PassSpec:
    name: str
    order: int  # declaration order
    kind: str
    queue: str
    impl: str | None
    requires: tuple[str, ...]
    side_effects: bool
    accesses: tuple[AccessSpec, ...]
    params: Mapping[str, Any]
    loc: Location
    requires_any: tuple[str, ...] = ()  # removed when the scene has none of these


@dataclass
class Spec:
    name: str
    source: str
    size: tuple[int, int]
    params: dict[str, Any]
    features: dict[str, int]
    scene_name: str | None
    resources: dict[str, ResourceSpec]
    passes: list[PassSpec]
    outputs: list[str]
    removed: list[tuple[str, str]]  # (pass, reason) for `requires` the scene lacks
    scene_source: str | None = None  # the scene file's path (the runtime builds its geometry)
    memory_policy: str | None = None  # the graph's default placement policy (``memory_policy:``)
    # resources whose count expression evaluated to 0 (``layers: "${scene.shadow_lights}"`` on a scene with
    # none): a placeholder of count 1 in ``resources``; the error is raised only when an
    # executed pass (after ``requires`` and culling) or an output uses it (``check_empty``)
    empty: dict[str, RGraphError] = field(default_factory=dict)


_SELECTOR = re.compile(r"^(?P<name>[^\[\]]+?)\s*(\[(?P<sel>[^\]]*)\])?$")
_SEL_PART = re.compile(r"^\s*(?P<key>mip|layer)\s*=\s*(?P<a>\d+)\s*(:\s*(?P<b>\d+)\s*)?$")
_SEL_PLURAL = re.compile(r"^\s*(mips|layers)\s*=")


class _Env:
    """Evaluates expression values with locations."""

    def __init__(self, params: Mapping[str, Any], features: Mapping[str, int]) -> None:
        self.values: dict[str, Any] = {f"params.{k}": v for k, v in params.items()}
        self.values.update({f"scene.{k}": v for k, v in features.items()})
        self.locals: frozenset[str] = frozenset()

    def bind(self, bindings: Mapping[str, int]) -> _Env:
        """This environment with a repeated pass's loop variables bound."""
        env = _Env({}, {})
        env.values = {**self.values, **bindings}
        env.locals = self.locals | frozenset(bindings)
        return env

    def text(self, text: str, where: Location) -> str:
        """``text`` with each ``${...}`` replaced by its integer value."""
        return substitute(text, self.values, self.locals, where) if "${" in text else text

    def number(self, value: Any, where: Located, *path: str | int) -> int | float:
        if isinstance(value, bool):
            raise RGraphError.at(where.loc(*path), f"expected a number, got {describe(value)}")
        if isinstance(value, int | float):
            return value
        try:
            expr = parse_value(value, self.locals)
            if expr is None:
                raise RGraphError.at(
                    where.loc(*path), f"expected a number or a '${{...}}' expression, got {describe(value)}"
                )
            result = expr.evaluate(self.values)
        except ExprError as exc:
            raise RGraphError.at(where.smap.inside_value((*where.path, *path), exc.offset), exc.message) from None
        return result

    def integer(self, value: Any, where: Located, *path: str | int) -> int:
        result = self.number(value, where, *path)
        if isinstance(result, float):
            if not result.is_integer():
                raise RGraphError.at(where.loc(*path), f"expected an integer, got {result}")
            result = int(result)
        return result


def resolve_params(source: GraphSource, overrides: Mapping[str, str]) -> dict[str, Any]:
    """Graph params with ``-p name=value`` overrides applied (types follow the default)."""
    params = {name: loc.model for name, loc in source.params.items()}
    for name, text in overrides.items():
        if name not in params:
            known = ", ".join(sorted(params)) or "none"
            raise RGraphError.in_file(
                "<command line>", f"unknown param {quote(name)}{did_you_mean(name, params)} (graph params: {known})"
            )
        params[name] = _parse_override(name, text, params[name])
    return params


def _parse_override(name: str, text: str, default: Any) -> Any:
    where = "<command line>"
    try:
        if isinstance(default, bool):
            low = text.strip().lower()
            if low not in ("true", "false", "1", "0"):
                raise ValueError
            return low in ("true", "1")
        if isinstance(default, int):
            return int(text, 0)
        if isinstance(default, float):
            value = float(text)
            if not math.isfinite(value):
                raise ValueError
            return value
    except ValueError:
        kind = type(default).__name__.replace("bool", "true/false").replace("int", "an integer").replace("float", "a number")
        raise RGraphError.in_file(where, f"param '{name}' expects {kind}, got {quote(text)}") from None
    return text


def specialize(
    source: GraphSource,
    *,
    features: Mapping[str, int],
    params: Mapping[str, Any],
    size: tuple[int, int],
    scene_name: str | None = None,
    limits: Limits = Limits(),
    quantities: Mapping[str, int] | None = None,
) -> Spec:
    """``quantities``: more ``scene.*`` names for expressions only (e.g. ``scene.draws``), not
    scene features (``requires`` and the plan's ``features`` do not see them)."""
    env = _Env(params, {**(quantities or {}), **features})
    resources: dict[str, ResourceSpec] = {}
    empty: dict[str, RGraphError] = {}
    for name, loc in source.resources.items():
        try:
            resources[name] = _resource(loc, env, size, limits)
        except _Empty as exc:
            resources[name], empty[name] = _resource(loc, env, size, limits, placeholder=True), exc
    outputs = _outputs(source, resources)
    passes: list[PassSpec] = []
    removed: list[tuple[str, str]] = []
    first_seen: dict[str, Location] = {}
    for template, located in source.passes.items():
        for name, bindings in instances(template, located, env):
            if name in first_seen:
                raise RGraphError.at(located.key_loc(), f"pass name '{name}' (from '{template}') is already "
                                                        f"used by the pass at {first_seen[name]}")
            first_seen[name] = located.key_loc()
            spec = _pass(name, len(passes), located, resources, env.bind(bindings))
            missing = [f for f in spec.requires if not features.get(f)]
            if missing:
                removed.append((name, "scene has no " + " and no ".join(missing)))
            elif spec.requires_any and not any(features.get(f) for f in spec.requires_any):
                removed.append((name, "scene has none of " + ", ".join(spec.requires_any)))
            passes.append(spec)
    _check_program_order(passes, resources)
    return Spec(
        name=source.name,
        source=str(source.path),
        size=size,
        params=dict(params),
        features=dict(features),
        scene_name=scene_name,
        resources=resources,
        passes=passes,
        outputs=outputs,
        removed=removed,
        memory_policy=source.memory_policy,
        empty=empty,
    )


class _Empty(RGraphError):
    """A resource count (layers, bytes, width, height, scale) whose expression evaluated to 0."""


def _count_error(where: Location, message: str, value: float, placeholder: bool, raw: Any) -> None:
    """Raise the out-of-range error of a count: ``_Empty`` for an expression (``raw`` a string)
    that evaluated to 0, nothing for it when making a placeholder; a literal 0 is an error."""
    empty = value == 0 and isinstance(raw, str)
    if empty and placeholder:
        return
    raise (_Empty if empty else RGraphError).at(where, message)


def check_empty(spec: Spec, passes: Sequence[PassSpec]) -> None:
    """An empty resource (``Spec.empty``) that an executed pass or an output uses is an error;
    otherwise only removed or culled passes (a shadow pass that ``requires: [shadow_lights]``)
    and dropped optional reads ever named it."""
    if not spec.empty:
        return
    used = {a.resource for p in passes for a in p.accesses} | set(spec.outputs)
    found = [d for name, err in spec.empty.items() if name in used for d in err.diagnostics]
    if found:
        raise RGraphError(found)


def _outputs(source: GraphSource, resources: dict[str, ResourceSpec]) -> list[str]:
    names: list[str] = []
    for out in source.outputs:
        if out.name not in resources:
            raise RGraphError.at(
                out.loc(), f"output '{out.name}' is not a resource{did_you_mean(out.name, resources)}"
            )
        if out.name in names:
            raise RGraphError.at(out.loc(), f"output '{out.name}' is listed twice")
        names.append(out.name)
    return names


def _resource(loc: Located, env: _Env, size: tuple[int, int], limits: Limits,
              placeholder: bool = False) -> ResourceSpec:
    """``placeholder``: counts of 0 become 1 (see ``Spec.empty``)."""
    model = loc.model
    if isinstance(model, AccelResource):
        return ResourceSpec(loc.name, "accel", model.lifetime, loc=loc.key_loc(), geometry=model.geometry)
    if not isinstance(model, ImageResource):
        nbytes = env.integer(model.bytes, loc, "bytes")
        if nbytes <= 0 or nbytes > limits.max_buffer_bytes:
            _count_error(loc.loc("bytes"), f"buffer size {nbytes} bytes is out of range (1 .. {limits.max_buffer_bytes})",
                         nbytes, placeholder, model.bytes)
            nbytes = 4
        return ResourceSpec(loc.name, model.kind, model.lifetime, bytes=nbytes, loc=loc.key_loc())
    try:
        fmt = formats.lookup(model.format)
    except KeyError:
        raise RGraphError.at(
            loc.loc("format"),
            f"unknown format {quote(model.format)}{did_you_mean(model.format.lower(), formats.names())}",
        ) from None
    width, height = _extent(model.size, loc, env, size, limits, placeholder)
    layers = env.integer(model.layers, loc, "layers")
    if not 1 <= layers <= limits.max_image_array_layers:
        _count_error(loc.loc("layers"),
                     f"layers must be 1 .. {limits.max_image_array_layers} (maxImageArrayLayers), got {layers}",
                     layers, placeholder, model.layers)
        layers = 1
    max_mips = int(math.floor(math.log2(max(width, height)))) + 1
    mips = env.integer(model.mips, loc, "mips")
    if not 1 <= mips <= max_mips:
        raise RGraphError.at(loc.loc("mips"), f"mips must be 1 .. {max_mips} for a {width}x{height} image, got {mips}")
    samples = env.integer(model.samples, loc, "samples")
    if samples not in VALID_SAMPLES:
        raise RGraphError.at(loc.loc("samples"), f"samples must be one of {', '.join(map(str, VALID_SAMPLES))}, got {samples}")
    return ResourceSpec(
        loc.name, "image", model.lifetime, fmt, (width, height, 1), layers, mips, samples, loc=loc.key_loc()
    )


def _extent(value: Any, loc: Located, env: _Env, size: tuple[int, int], limits: Limits,
            placeholder: bool = False) -> tuple[int, int]:
    limit = limits.max_image_dimension_2d
    if value == "output":
        dims = size
    elif isinstance(value, ScaleSize):
        scale = env.number(value.scale, loc, "size", "scale")
        if not 0 < scale <= MAX_SCALE:
            _count_error(loc.loc("size", "scale"), f"scale must be in (0, {MAX_SCALE:g}], got {scale}", scale,
                         placeholder, value.scale)
            scale = 1.0
        dims = (max(1, int(size[0] * scale)), max(1, int(size[1] * scale)))
    elif isinstance(value, list):
        if len(value) != 2:
            raise RGraphError.at(loc.loc("size"), f"size must be [width, height], got {len(value)} values")
        dims = (env.integer(value[0], loc, "size", 0), env.integer(value[1], loc, "size", 1))
    else:  # pydantic allows only the three forms; keep the type checker honest
        raise RGraphError.at(loc.loc("size"), "size must be 'output', [width, height] or {scale: s}")
    for i, d in enumerate(dims):
        if not 1 <= d <= limit:
            where = loc.loc("size", i) if isinstance(value, list) else loc.loc("size")
            _count_error(where, f"image {('width', 'height')[i]} {d} is out of range (1 .. {limit}, maxImageDimension2D)",
                         d, placeholder, value[i] if isinstance(value, list) else None)
    return (max(1, dims[0]), max(1, dims[1]))


def _selector(template: str, located: Located, section: str, env: _Env) -> tuple[str, dict[str, tuple[int, int]]]:
    where = located.key_loc(section, template)
    key = env.text(template, where)
    match = _SELECTOR.match(key)
    if not match:
        raise RGraphError.at(where, f"bad resource reference '{key}' (expected NAME or NAME[layer=a:b, mip=c])")
    ranges: dict[str, tuple[int, int]] = {}
    sel = match.group("sel")
    if sel is not None:
        for part in sel.split(","):
            pm = _SEL_PART.match(part)
            plural = _SEL_PLURAL.match(part)
            if plural:
                raise RGraphError.at(where, f"bad subresource selector '{part.strip()}' in '{key}': the axis is "
                                            f"'{plural.group(1)[:-1]}' (mip=a:b, layer=a:b), not '{plural.group(1)}'")
            if not pm:
                raise RGraphError.at(
                    where, f"bad subresource selector '{part.strip()}' in '{key}' (expected layer=a:b or mip=a:b, half-open)"
                )
            axis = "mips" if pm.group("key") == "mip" else "layers"
            a = int(pm.group("a"))
            b = int(pm.group("b")) if pm.group("b") is not None else a + 1
            if b <= a:
                raise RGraphError.at(where, f"empty subresource range {axis[:-1]}={a}:{b} in '{key}' (ranges are half-open)")
            if axis in ranges:
                raise RGraphError.at(where, f"'{axis[:-1]}' selected twice in '{key}'")
            ranges[axis] = (a, b)
    return match.group("name").strip(), ranges


def _pass(name: str, order: int, located: Located, resources: dict[str, ResourceSpec], env: _Env) -> PassSpec:
    model = located.model
    if model.kind not in QUEUE_PASS_KINDS[model.queue]:
        raise RGraphError.at(located.loc("queue"), f"a {model.kind} pass cannot run on the {model.queue} queue")
    accesses: list[AccessSpec] = []
    for section in ("reads", "writes"):
        for key, entries in getattr(model, section).items():
            res_name, ranges = _selector(key, located, section, env)
            res = resources.get(res_name)
            if res is None:
                raise RGraphError.at(
                    located.key_loc(section, key),
                    f"pass '{name}' {section[:-1]}s undefined resource {quote(res_name)}{did_you_mean(res_name, resources)}",
                )
            for i, entry in enumerate(entries):
                where = located.smap.value((*located.path, section, key, i)) if len(entries) > 1 else located.loc(section, key)
                accesses.append(_access(name, model.kind, section, res, ranges, entry, where, located, key))
    _check_overlaps(name, accesses)
    return PassSpec(
        name=name,
        order=order,
        kind=model.kind,
        queue=model.queue,
        impl=model.impl,
        requires=tuple(model.requires),
        requires_any=tuple(model.requires_any),
        side_effects=model.side_effects,
        accesses=tuple(accesses),
        params=dict(model.params),
        loc=located.key_loc(),
    )


def _a(kind: str) -> str:
    """``an image``, ``a buffer``, ``an accel``."""
    return ("an " if kind[0] in "aeiou" else "a ") + kind


def _access(pass_name, pass_kind, section, res, ranges, entry, where, located, key) -> AccessSpec:
    usage = entry.usage
    if res.kind not in USAGE_RESOURCE_KINDS[usage]:
        kinds = " or ".join(_a(k) for k in sorted(USAGE_RESOURCE_KINDS[usage]))
        raise RGraphError.at(where, f"usage '{usage}' needs {kinds}, but '{res.name}' is {_a(res.kind)}")
    if pass_kind not in USAGE_PASS_KINDS[usage]:
        kinds = ", ".join(sorted(USAGE_PASS_KINDS[usage]))
        raise RGraphError.at(where, f"usage '{usage}' is not possible in a {pass_kind} pass (only in: {kinds})")
    writes = usage in WRITE_USAGES
    if section == "reads" and writes:
        raise RGraphError.at(where, f"usage '{usage}' writes '{res.name}'; list it under 'writes'")
    if section == "writes" and not writes:
        raise RGraphError.at(where, f"usage '{usage}' only reads '{res.name}'; list it under 'reads'")
    if entry.optional and section == "writes":
        raise RGraphError.at(where, "only reads can be optional")
    if res.format is not None and not res.format.supports(usage):
        raise RGraphError.at(where, f"format {res.format.name} does not support usage '{usage}'{_format_hint(usage)}")
    if entry.stages is not None and pass_kind != "raster" and not set(entry.stages) <= _KIND_STAGES[pass_kind]:
        raise RGraphError.at(where, f"stages {entry.stages} are not stages of a {pass_kind} pass")
    mips = layers = None
    if res.kind == "image":
        mips = ranges.get("mips", (0, res.mips))
        layers = ranges.get("layers", (0, res.layers))
        for axis, (a, b), count in (("mip", mips, res.mips), ("layer", layers, res.layers)):
            if b > count:
                raise RGraphError.at(
                    located.key_loc(section, key),
                    f"{axis} range {a}:{b} is outside '{res.name}', which has {count} {axis}{'s' if count != 1 else ''}",
                )
    elif ranges:
        raise RGraphError.at(located.key_loc(section, key), f"'{res.name}' is {_a(res.kind)}: it has no mips or layers")
    return AccessSpec(
        res.name, usage, writes, mips, layers, tuple(entry.stages) if entry.stages else None, entry.optional, where
    )


_KIND_STAGES = {
    "compute": {"compute"},
    "raytrace": {"raygen", "miss", "closest_hit", "any_hit", "intersection", "callable"},
    "transfer": set(),
}


def _format_hint(usage: str) -> str:
    return {
        "depth_attachment": " (needs a depth format such as d32_sfloat)",
        "depth_read": " (needs a depth format such as d32_sfloat)",
        "color_attachment": " (needs a color format)",
        "color_attachment_blend": " (needs a color format)",
    }.get(usage, " (storage needs a storage-capable format such as r32_sfloat or r16g16b16a16_sfloat; sRGB formats cannot be storage)" if usage.startswith("storage") else "")


def _overlap(a: AccessSpec, b: AccessSpec) -> bool:
    if a.mips is None or b.mips is None or a.layers is None or b.layers is None:
        return True
    return a.mips[0] < b.mips[1] and b.mips[0] < a.mips[1] and a.layers[0] < b.layers[1] and b.layers[0] < a.layers[1]


_COMBINABLE = {frozenset({"depth_read", "sampled"})}


def _check_overlaps(pass_name: str, accesses: list[AccessSpec]) -> None:
    """A resource appears once per pass, except disjoint ranges and allowed combinations."""
    for i, a in enumerate(accesses):
        for b in accesses[:i]:
            if a.resource != b.resource or not _overlap(a, b):
                continue
            if a.usage == b.usage:
                raise RGraphError.at(a.loc, f"pass '{pass_name}' uses '{a.resource}' as {a.usage} twice")
            if frozenset({a.usage, b.usage}) in _COMBINABLE:
                continue
            if a.write or b.write:
                raise RGraphError.at(
                    a.loc,
                    f"pass '{pass_name}' uses overlapping parts of '{a.resource}' both as {b.usage} and {a.usage}; "
                    "use disjoint subresource ranges or a read-write usage",
                )
            if _layout_class(a.usage) != _layout_class(b.usage):
                raise RGraphError.at(
                    a.loc, f"pass '{pass_name}' reads '{a.resource}' as {b.usage} and {a.usage}, which need different layouts"
                )


def _layout_class(usage: str) -> str:
    return {"sampled": "ro", "depth_read": "ro", "storage_read": "general", "transfer_src": "src"}.get(usage, usage)


def _check_program_order(passes: list[PassSpec], resources: dict[str, ResourceSpec]) -> None:
    """A non-optional read of a transient resource needs an earlier write of every cell it reads."""
    written: dict[str, set[tuple[int, int]]] = {}
    for p in passes:
        for a in p.accesses:
            res = resources[a.resource]
            if res.lifetime in ("persistent", "imported") or a.write or a.optional:
                continue
            cells = _cells(a)
            have = written.get(a.resource, set())
            if not cells <= have:
                if not have:
                    msg = f"pass '{p.name}' reads '{a.resource}' before any pass writes it"
                else:
                    msg = f"pass '{p.name}' reads parts of '{a.resource}' that no earlier pass writes"
                raise RGraphError.at(a.loc, msg + " (declaration order is program order)")
        for a in p.accesses:
            if a.write:
                written.setdefault(a.resource, set()).update(_cells(a))


def _cells(a: AccessSpec) -> set[tuple[int, int]]:
    if a.mips is None or a.layers is None:
        return {(0, 0)}
    return {(m, layer) for m in range(*a.mips) for layer in range(*a.layers)}
