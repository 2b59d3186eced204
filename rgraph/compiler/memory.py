"""Resource memory: requirements from a provider, lifetimes, classes, and placement.

Sizes and alignments come from the memory-requirements provider (a live device or a
captured device profile), never from a formula here. Transient resources are placed by the
allocator policy and may alias; persistent, imported and output resources get their own
allocation each.
"""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

from rgraph.errors import RGraphError
from rgraph.memory.model import Block, Heap, Placement, PlacementStats
from rgraph.native import load
from rgraph.plan.builders import builder
from rgraph.spec.specialize import PassSpec, ResourceSpec

Requirements = tuple[int, int, int]


class MemoryRequirementsProvider(Protocol):
    def image(
        self, format_vk_name: str, extent: Sequence[int], mips: int, layers: int, samples: int,
        usage_names: Sequence[str],
    ) -> Requirements: ...

    def buffer(self, size: int, usage_names: Sequence[str]) -> Requirements: ...


@dataclass(frozen=True, slots=True)
class Requirement:
    """What the provider says one resource needs, and its tiling (optimal images, linear buffers)."""

    bytes: int
    alignment: int
    memory_type_bits: int
    tiling: str


@dataclass(frozen=True, slots=True)
class ResourceMemory:
    """A used resource's memory as the plan records it (the measure phase's result)."""

    bytes: int
    alignment: int
    memory_type_bits: int
    memory_class: str
    usages: tuple[str, ...]  # sorted union over the kept passes
    first: int  # executed pass indices
    last: int


_requirement, _resource_memory = builder(Requirement), builder(ResourceMemory)  # one per used resource
_heap = builder(Heap)  # one per resource placed apart

#: The compiled mirror of :func:`requirements_python`, :func:`resource_memory_python`,
#: :func:`alias_sources_python`, ``phases._culled_only_python``, the whole measure phase
#: (``phases._measure_python``: ``measure``), ``phases.place``'s candidates with
#: ``place_resources``' split (``split_transients``) and ``place_resources``' loops
#: (``rgraph/compiler/_memory.pyx``), None where it is not built or ``RGRAPH_NATIVE=0``.
NATIVE = load("rgraph.compiler._memory")

# Usages that set the same VkBufferUsageFlags bit (STORAGE_BUFFER) have the same requirements.
_SAME_BUFFER_FLAG = {"storage_read": "storage_rw", "storage_write": "storage_rw",
                     "accel_build": "accel_storage", "accel_read": "accel_storage"}


def usages_by_resource(passes: Sequence[PassSpec]) -> dict[str, set[str]]:
    """Per resource: the usages ``passes`` make of it (raytrace indirect arguments also
    ``trace_indirect``), as ``rgraph.compiler.trace`` records them for the executed passes."""
    used: dict[str, set[str]] = {}
    for p in passes:
        raytrace = p.kind == "raytrace"
        for a in p.accesses:
            found = used.get(a.resource)
            if found is None:
                found = used[a.resource] = {a.usage}
            else:
                found.add(a.usage)
            if raytrace and a.usage == "indirect":  # vkCmdTraceRaysIndirectKHR: a device address
                found.add("trace_indirect")
    return used


def requirements(
    resources: Mapping[str, ResourceSpec],
    used: Mapping[str, set[str]],
    outputs: Sequence[str],
    provider: MemoryRequirementsProvider,
) -> dict[str, Requirement]:
    """The requirement of each used resource, in name order (compiled where built)."""
    if NATIVE is None:
        return requirements_python(resources, used, outputs, provider)
    return NATIVE.requirements(resources, used, outputs, provider, _SAME_BUFFER_FLAG)


def requirements_python(
    resources: Mapping[str, ResourceSpec],
    used: Mapping[str, set[str]],
    outputs: Sequence[str],
    provider: MemoryRequirementsProvider,
) -> dict[str, Requirement]:
    out = {}
    kept = set(outputs)  # a list: 5,000 side-effect outputs made this quadratic
    for name in sorted(used):
        res = resources[name]
        usages = sorted(used[name] | ({"transfer_src"} if name in kept or res.lifetime == "output" else set()))
        try:
            if res.is_image:
                assert res.format is not None
                size, align, bits = provider.image(
                    res.format.vk_name, res.extent, res.mips, res.layers, res.samples, usages
                )
                tiling = "optimal"
            else:
                flags = sorted({_SAME_BUFFER_FLAG.get(u, u) for u in usages})
                size, align, bits = provider.buffer(res.bytes, flags)
                tiling = "linear"
        except RGraphError as err:
            raise RGraphError.at(res.loc, f"resource '{name}': {err.first.message}") from None
        out[name] = _requirement(size, align, bits, tiling)
    return out


def memory_classes(reqs: Mapping[str, Requirement]) -> dict[str, str]:
    """Class per resource: tiling, plus the memoryTypeBits when a tiling has several."""
    bits_by_tiling: dict[str, set[int]] = {}
    for r in reqs.values():
        bits_by_tiling.setdefault(r.tiling, set()).add(r.memory_type_bits)
    out = {}
    for name, r in reqs.items():
        cls = f"device_local_{r.tiling}"
        out[name] = cls if len(bits_by_tiling[r.tiling]) == 1 else f"{cls}_types_{r.memory_type_bits:x}"
    return out


def resource_memory(
    reqs: Mapping[str, Requirement], used: Mapping[str, set[str]], spans: Mapping[str, tuple[int, int]]
) -> dict[str, ResourceMemory]:
    """Requirements, classes, usages and lifetimes of the used resources, in name order
    (compiled where built)."""
    if NATIVE is None:
        return resource_memory_python(reqs, used, spans)
    return NATIVE.resource_memory(reqs, used, spans)


def resource_memory_python(
    reqs: Mapping[str, Requirement], used: Mapping[str, set[str]], spans: Mapping[str, tuple[int, int]]
) -> dict[str, ResourceMemory]:
    classes = memory_classes(reqs)
    return {
        name: _resource_memory(r.bytes, r.alignment, r.memory_type_bits, classes[name], tuple(sorted(used[name])),
                             spans[name][0], spans[name][1])
        for name, r in reqs.items()
    }


def place_resources(
    resources: Mapping[str, ResourceSpec],
    memory: Mapping[str, ResourceMemory],
    policy: str,
    outputs: Sequence[str],
    conflicts: Mapping[str, set[str]] | None = None,
    split: tuple[list[str], list[str]] | None = None,
) -> Placement:
    """Place transients with ``policy``; give every other resource its own heap.
    ``conflicts``: transients that may not alias although apart in time (queue_order.py).
    ``split`` (compiled path only): ``NATIVE.split(resources, memory, outputs)``, made already."""
    from rgraph.memory import _NATIVE as fit
    from rgraph.memory import place

    if NATIVE is None:
        kept = set(outputs)
        aliasable = [n for n in sorted(memory) if resources[n].lifetime == "transient" and n not in kept]
        blocks = [
            Block(n, m.first, m.last, m.bytes, m.alignment, m.memory_class) for n in aliasable for m in (memory[n],)
        ]
    else:  # the same names, and the same blocks built in C: as columns where built (no Block each)
        aliasable, rest = NATIVE.split(resources, memory, outputs) if split is None else split
        if fit is None:
            blocks = NATIVE.blocks(aliasable, memory)
        else:
            blocks = fit.Columns(aliasable, *NATIVE.columns(aliasable, memory))
    placed = place(blocks, policy, conflicts=conflicts)
    offsets = dict(placed.offsets)
    heaps = list(placed.heaps)
    if NATIVE is None:
        extra = 0
        for n in sorted(set(memory) - set(aliasable)):
            m = memory[n]
            heap = _heap(len(heaps), m.bytes, m.memory_class, m.alignment)
            heaps.append(heap)
            offsets[n] = (heap.id, 0)
            extra += m.bytes
    else:  # the same loop over the same names, compiled
        extra = NATIVE.dedicated(rest, memory, heaps, offsets, _heap)
    s = placed.stats
    stats = PlacementStats(
        s.policy, s.peak_bytes + extra, s.lower_bound_bytes + extra, s.unaliased_bytes + extra,
        s.allocations + len(memory) - len(aliasable), s.seconds,
    )
    return Placement(offsets, heaps, stats)


def alias_sources(placement: Placement, memory: Mapping[str, ResourceMemory]) -> dict[str, list[str]]:
    """:func:`alias_sources_python`, compiled where built."""
    if NATIVE is None:
        return alias_sources_python(placement, memory)
    return NATIVE.alias_sources(placement, memory)


def alias_sources_python(placement: Placement, memory: Mapping[str, ResourceMemory]) -> dict[str, list[str]]:
    """For each resource, the earlier resources whose memory it reuses and that it must wait for.

    An earlier overlapping resource is skipped when a later one, itself overlapping both,
    already waited for it (the chain covers it). Earlier occupants are visited latest first
    and the walk stops once one that started after them holds all of the resource's bytes,
    so a long chain of reuses costs a few steps per resource, not the whole history."""
    by_heap: dict[int, list[str]] = {}
    for name, (heap, _) in placement.offsets.items():
        by_heap.setdefault(heap, []).append(name)
    out: dict[str, list[str]] = {}
    for names in by_heap.values():
        if len(names) < 2:
            continue
        # per resource: (first pass, last pass, first byte, end byte)
        span = {}
        for n in names:
            m = memory[n]
            off = placement.offsets[n][1]
            span[n] = (m.first, m.last, off, off + m.bytes)
        ordered = sorted(names, key=lambda n: (span[n][0], n))
        by_last = sorted(names, key=lambda n: (span[n][1], n))
        lasts = [span[n][1] for n in by_last]
        for r in ordered:
            r_first, _, r_lo, r_hi = span[r]
            visited: list[tuple[int, int, int]] = []  # (first, first byte, end byte) of earlier occupants
            stop = -1  # occupants that ended before this first are covered by one holding all of r
            keep = []
            for k in range(bisect_left(lasts, r_first) - 1, -1, -1):
                p = by_last[k]
                p_first, p_last, p_lo, p_hi = span[p]
                if p_last < stop:
                    break
                if not (r_lo < p_hi and p_lo < r_hi):
                    continue
                lo, hi = max(p_lo, r_lo), min(p_hi, r_hi)  # the bytes both hold
                if not any(first > p_last and v_lo <= lo and hi <= v_hi for first, v_lo, v_hi in visited):
                    keep.append(p)
                visited.append((p_first, p_lo, p_hi))
                if p_lo <= r_lo and r_hi <= p_hi:
                    stop = max(stop, p_first)
            if keep:
                out[r] = sorted(keep, key=lambda n: (span[n][0], n))
    return out
