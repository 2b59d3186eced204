"""Several devices (FORMAT.md section 6): sort-first / sort-last as a transformation after culling.

    partition(spec, culled passes, split) -> Partition   (pure: where to cut, what crosses)
    device_specs(spec, partition, split)  -> one Spec per device
    compile_split(...)                    -> per-device plans merged (rgraph.plan.devices.merge)

**Where the composite goes** is decided from the graph, walking the culled passes in
executed order and tracking which resources hold only a device's *share* ("split"):

- sort-first: a raster pass with an output-sized attachment is *tiled*: it runs on every
  device with ``params["rgraph.scissor"] = [x, y, w, h]`` (a horizontal band; the viewport
  stays the full screen, so the projection is unchanged and every pixel of the band is
  computed exactly as on one device). Its writes become split.
- sort-last: a raster pass with an output-sized depth access gets
  ``params["rgraph.draws"] = [device, devices]`` (its share of the scene's draws); its
  writes become split (colour + depth, composited with the depth test).
- A pass that reads a split resource other than as an attachment of the same pixel
  (sampled, storage, transfer: a blur, AO, SSS, bloom may read neighbours) is the *cut*:
  it and every later pass run after the composite, on device 0 only. The graph cannot say
  that a sampled read stays on its own pixel, so the rule is conservative.
- Passes writing no output-sized attachment and reading nothing split (light setup,
  **shadow maps**, LUTs) are replicated whole on every device that needs them: a tile or
  a share of draws samples the shadow map anywhere, so splitting it would need a
  min-composite and one more cross-device copy and wait before the first lit pass;
  re-rendering it per device costs one shadow pass per device and no transfer.

Split resources that the cut's side reads (or outputs, or persistent ones) *cross*: device
``d > 0`` copies its band (sort-first) or whole image (sort-last) into a host-visible
buffer (``X.download``, read back to the host), device 0 waits for it and copies it into place (``X.upload<d>``,
the sort-first composite) or into ``X.remote<d>`` that ``composite<d>`` depth-tests in.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from rgraph.errors import RGraphError
from rgraph.plan.devices import COMPOSITE_IMPL, DOWNLOAD_IMPL, DRAWS, PROBE_INDEX, SCISSOR, UPLOAD_IMPL  # noqa: F401
from rgraph.spec.specialize import AccessSpec, PassSpec, ResourceSpec, Spec

if TYPE_CHECKING:
    from rgraph.plan.model import Plan

SPLITS = ("sort-first", "sort-last")
BALANCES = ("static", "dynamic")
LOCAL_USAGES = frozenset({"color_attachment", "color_attachment_blend", "depth_attachment", "depth_read"})


@dataclass(frozen=True)
class Split:
    """``--devices N --split MODE --balance B``; ``weights``: each device's share (default equal)."""

    devices: int
    mode: str
    balance: str = "static"
    weights: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        where = "<command line>"
        if self.devices < 1:
            raise RGraphError.in_file(where, f"--devices: expected at least 1 device, got {self.devices}")
        if self.mode not in SPLITS:
            raise RGraphError.in_file(where, f"--split expects one of {', '.join(SPLITS)}, got '{self.mode}'")
        if self.balance not in BALANCES:
            raise RGraphError.in_file(where, f"--balance expects one of {', '.join(BALANCES)}, got '{self.balance}'")
        if self.weights is not None and (len(self.weights) != self.devices or min(self.weights) <= 0):
            raise RGraphError.in_file(where, f"balance weights: expected {self.devices} positive numbers")


def bands(height: int, split: Split) -> list[tuple[int, int]]:
    """``(y, rows)`` of each device's horizontal band, top to bottom, covering ``height`` exactly."""
    weights = split.weights or (1.0,) * split.devices
    total = sum(weights)
    edges = [0]
    acc = 0.0
    for w in weights[:-1]:
        acc += w
        edges.append(min(height, max(edges[-1], round(height * acc / total))))
    edges.append(height)
    return [(a, b - a) for a, b in zip(edges, edges[1:], strict=False)]


@dataclass(frozen=True)
class Partition:
    prefix: tuple[PassSpec, ...]  # replicated on every device (tiled passes marked in ``tiled``)
    suffix: tuple[PassSpec, ...]  # after the composite, device 0 only
    tiled: frozenset[str]  # passes restricted to a band / a share of draws
    crossing: tuple[str, ...]  # split resources device 0 needs whole (name order)
    depth: str | None  # sort-last: the split depth the composite tests against
    cut: str | None  # first pass after the composite
    reason: str


def _screen(spec: Spec, name: str) -> bool:
    r = spec.resources[name]
    return r.is_image and tuple(r.extent[:2]) == tuple(spec.size)


def _tileable(spec: Spec, p: PassSpec, mode: str) -> bool:
    if p.kind != "raster":
        return False
    attach = [a for a in p.accesses if a.usage in LOCAL_USAGES and _screen(spec, a.resource)]
    if mode == "sort-last":
        attach = [a for a in attach if a.usage.startswith("depth")]
    return bool(attach) and all(a.mips in (None, (0, 1)) for a in attach)


def partition(spec: Spec, passes: Sequence[PassSpec], mode: str) -> Partition:
    """Where the composite goes (module docstring), from the culled passes in executed order."""
    split: set[str] = set()
    tiled: set[str] = set()
    cut, reason = None, "no pass reads a split result: the composite is at the end"
    prefix: list[PassSpec] = []
    for p in passes:
        far = [a for a in p.accesses if a.resource in split and not a.write and a.usage not in LOCAL_USAGES]
        if far:
            cut, reason = p.name, f"pass '{p.name}' reads split '{far[0].resource}' as {far[0].usage}"
            break
        if _tileable(spec, p, mode):
            tiled.add(p.name)
            split.update(a.resource for a in p.accesses if a.write)
        elif any(a.resource in split for a in p.accesses):
            bad = next(a for a in p.accesses if a.resource in split)
            cut, reason = p.name, f"pass '{p.name}' ({p.kind}) accesses split '{bad.resource}' whole"
            break
        prefix.append(p)
    rest = tuple(passes[len(prefix):])
    last = max((i for i, p in enumerate(prefix) if p.name in tiled), default=-1)
    suffix = tuple(prefix[last + 1:]) + rest  # whole passes after the last tiled one need not be replicated
    prefix = prefix[:last + 1]
    used_after = {a.resource for p in suffix for a in p.accesses}
    crossing = sorted(r for r in split if r in used_after or r in spec.outputs
                      or spec.resources[r].lifetime != "transient")
    depth = None
    if mode == "sort-last" and crossing:
        depths = sorted(r for r in split if _screen(spec, r) and spec.resources[r].format is not None
                        and spec.resources[r].format.has_depth)
        crossing = sorted(set(crossing) | set(depths))
        if len(depths) != 1:
            raise RGraphError.in_file(spec.source, f"--split sort-last: the composite needs exactly one split depth "
                                                   f"image, the graph splits {depths or 'none'}")
        depth = depths[0]
    return Partition(tuple(prefix), suffix, frozenset(tiled), tuple(crossing), depth, cut, reason)


def _texel_bytes(r: ResourceSpec) -> int:
    assert r.format is not None
    return r.format.block_bytes // (r.format.block_extent[0] * r.format.block_extent[1])


def _rect(spec: Spec, split: Split, device: int) -> list[int]:
    w, h = spec.size
    if split.mode == "sort-last":
        return [0, 0, w, h]
    y, rows = bands(h, split)[device]
    return [0, y, w, rows]


def _transfer(name: str, order: int, impl: str, accesses: list[AccessSpec], params: dict, loc) -> PassSpec:
    # a copy into place writes part of its target, which a later copy does not make dead (cull)
    return PassSpec(name=name, order=order, kind="transfer", queue="graphics", impl=impl, requires=(),
                    side_effects=impl == UPLOAD_IMPL, accesses=tuple(accesses), params=params, loc=loc)


def _access(resource: str, usage: str, write: bool, r: ResourceSpec, loc) -> AccessSpec:
    whole = ((0, 1), (0, r.layers)) if r.is_image else (None, None)
    return AccessSpec(resource, usage, write, whole[0], whole[1], None, False, loc)


def _staging(name: str, r: ResourceSpec, rect: list[int], lifetime: str) -> ResourceSpec:
    return ResourceSpec(name=name, kind="buffer", lifetime=lifetime, bytes=rect[2] * rect[3] * r.layers * _texel_bytes(r),
                        loc=r.loc)


def device_specs(spec: Spec, part: Partition, split: Split) -> list[Spec]:
    """One Spec per device: device 0 renders its share, receives the others' and runs the rest."""
    n = split.devices
    order = max((p.order for p in spec.passes), default=0) + 1
    loc = spec.passes[0].loc if spec.passes else None

    def tiled(p: PassSpec, d: int) -> PassSpec:
        if p.name not in part.tiled:
            return p
        extra = {SCISSOR: _rect(spec, split, d)} if split.mode == "sort-first" else {DRAWS: [d, n]}
        # on device 0 the copy into place overwrites part of what it wrote: not dead (cull)
        return replace(p, params={**p.params, **extra}, side_effects=p.side_effects or d == 0)

    result: list[Spec] = []
    receive: list[PassSpec] = []
    resources0 = dict(spec.resources)
    for d in range(1, n):
        rect = _rect(spec, split, d)
        resources = dict(spec.resources)
        passes = [tiled(p, d) for p in part.prefix]
        for x in part.crossing:
            r = spec.resources[x]
            tile, landing = f"{x}.tile", f"{x}.from{d}"
            resources[tile] = _staging(tile, r, rect, "output")
            resources0[landing] = _staging(landing, r, rect, "imported")
            passes.append(_transfer(f"{x}.download", order, DOWNLOAD_IMPL,
                                    [_access(x, "transfer_src", False, r, loc), _access(tile, "transfer_dst", True,
                                                                                        resources[tile], loc)],
                                    {"rect": rect}, loc))
            order += 1
            params = {"rect": rect, "copy_from": {"device": d, "pass": f"{x}.download@{d}"}}
            if split.mode == "sort-first":
                receive.append(_transfer(f"{x}.upload{d}", order, UPLOAD_IMPL,
                                         [_access(landing, "transfer_src", False, resources0[landing], loc),
                                          _access(x, "transfer_dst", True, r, loc)], params, loc))
            else:
                remote = f"{x}.remote{d}"
                resources0[remote] = replace(r, name=remote, lifetime="transient")
                receive.append(_transfer(f"{x}.upload{d}", order, UPLOAD_IMPL,
                                         [_access(landing, "transfer_src", False, resources0[landing], loc),
                                          _access(remote, "transfer_dst", True, resources0[remote], loc)],
                                         params, loc))
            order += 1
        result.append(replace(spec, resources=resources, passes=passes,
                              outputs=[f"{x}.tile" for x in part.crossing]))
    if split.mode == "sort-last" and part.crossing:
        for d in range(1, n):
            receive.append(_composite(spec, part, d, order, loc))
            order += 1
    passes0 = [tiled(p, 0) for p in part.prefix] + receive + list(part.suffix)
    result.insert(0, replace(spec, resources=resources0, passes=passes0))
    return result


def _composite(spec: Spec, part: Partition, d: int, order: int, loc) -> PassSpec:
    """Sort-last: draw device ``d``'s colour + depth over device 0's where it is nearer (depth test)."""
    assert part.depth is not None
    accesses = []
    for x in part.crossing:
        r = spec.resources[x]
        accesses.append(_access(f"{x}.remote{d}", "sampled", False, r, loc))
        usage = "depth_attachment" if x == part.depth else "color_attachment_blend"
        accesses.append(_access(x, usage, True, r, loc))
    return PassSpec(name=f"composite{d}", order=order, kind="raster", queue="graphics", impl=COMPOSITE_IMPL,
                    requires=(), side_effects=True, accesses=tuple(accesses),
                    params={"depth": part.depth, "from_device": d}, loc=loc)


def compile_split(spec: Spec, split: Split, **options) -> Plan:
    """Spec -> one merged multi-device plan (``rgraph.plan.devices``); options as ``compilation``."""
    from rgraph.compiler.pipeline import compilation
    from rgraph.ir.cull import cull as cull_spec
    from rgraph.plan.devices import merge

    culling = cull_spec(spec)
    # every pass keeps its one-device index for the probe's values (rgraph.probe.semantics)
    kept_passes = [replace(p, params={**p.params, PROBE_INDEX: i}) for i, p in enumerate(culling.passes)]
    part = partition(spec, kept_passes, split.mode)
    kept = replace(spec, passes=kept_passes, removed=[])
    plans = []
    for sub in device_specs(kept, part, split):
        plan = compilation(sub, **options).plan
        assert plan is not None
        plans.append(plan)
    info = {"devices": split.devices, "split": split.mode, "balance": split.balance, "cut": part.cut,
            "reason": part.reason, "crossing": list(part.crossing), "tiled": sorted(part.tiled)}
    if split.mode == "sort-first":
        info["bands"] = [list(b) for b in bands(spec.size[1], split)]
    full = compilation(spec, **options).plan
    assert full is not None
    from rgraph.plan import dump, load

    return load(dump(merge(plans, info, culled=full.culled)))  # canonical (lists in params as the file has them)
