"""The emit phase: the compiler's results -> the typed plan (``rgraph.plan.model``).

Everything is sorted or in a defined order here, so that the same inputs give the same
plan (and ``rgraph.plan.dump`` the same bytes).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from rgraph.defaults import DEFAULT_SCHEDULE
from rgraph.native import load
from rgraph.plan import model as pm
from rgraph.plan.builders import builder

if TYPE_CHECKING:
    from rgraph.compiler.phases import Compilation

SIGNAL_STAGES = ("ALL_COMMANDS",)

# The plan values built per access, pass and resource (rgraph.plan.builders); barriers come
# from the sync phase as plan values.
_Access, _Pass, _Resource = (builder(c) for c in (pm.Access, pm.PlanPass, pm.PlanResource))
_Wait, _Signal, _Culled = (builder(c) for c in (pm.Wait, pm.Signal, pm.Culled))
_Heap = builder(pm.Heap)

#: The compiled mirror of :func:`_passes_python`, :func:`_resources_python` and
#: :func:`_culled_python` (``rgraph/compiler/_emit.pyx``), None where it is not built or
#: ``RGRAPH_NATIVE=0``.
NATIVE = load("rgraph.compiler._emit")


def _frozen(mapping: Mapping[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(dict(sorted(mapping.items()))) if mapping else pm.EMPTY


def _frozen_json(value: Any) -> Any:
    """A JSON value read-only, objects in their order, lists as tuples (as the loader reads it)."""
    if isinstance(value, Mapping):
        return MappingProxyType({k: _frozen_json(v) for k, v in value.items()})
    if isinstance(value, list | tuple):
        return tuple(_frozen_json(v) for v in value)
    return value


def _passes(c: Compilation) -> tuple[pm.PlanPass, ...]:
    """The plan's passes (compiled where built)."""
    if NATIVE is None:
        return _passes_python(c)
    sync, trace = c.sync, c.trace
    assert sync is not None and trace is not None
    return NATIVE.passes(list(c.passes), trace.accesses, sync.barriers, sync.releases, sync.waits, sync.signals,
                         sync.signal_values, _frozen, SIGNAL_STAGES)


def _passes_python(c: Compilation) -> tuple[pm.PlanPass, ...]:
    passes, sync, trace = c.passes, c.sync, c.trace
    assert sync is not None and trace is not None
    signals, signal_values = sync.signals, sync.signal_values
    barriers, releases, waits = sync.barriers, sync.releases, sync.waits
    out = []
    for i, (p, accesses) in enumerate(zip(passes, trace.accesses, strict=True)):
        params = p.params
        out.append(_Pass(
            p.name, i, 0, p.queue, p.kind, p.impl, _frozen(params) if params else pm.EMPTY, tuple(accesses),
            barriers[i], releases[i],
            waits[i],
            (_Signal(p.queue, signal_values[i], SIGNAL_STAGES),) if signals[i] else (),
        ))
    return tuple(out)


def _resources(c: Compilation) -> tuple[pm.PlanResource, ...]:
    """The plan's resources, in name order (compiled where built)."""
    if NATIVE is None:
        return _resources_python(c)
    sync, placement = c.sync, c.placement
    assert sync is not None and placement is not None
    return NATIVE.resources(c.spec.resources, c.memory, set(c.spec.outputs), sync.initial, sync.final,
                            placement.offsets, _frozen_json)


def _resources_python(c: Compilation) -> tuple[pm.PlanResource, ...]:
    spec, sync, placement, memory = c.spec, c.sync, c.placement, c.memory
    assert sync is not None and placement is not None
    out = []
    outputs = set(c.spec.outputs)
    initial, final, offsets = sync.initial, sync.final, placement.offsets
    for name in sorted(memory):
        res, mem = spec.resources[name], memory[name]
        heap, offset = offsets[name]
        lifetime = "output" if (name in outputs and res.lifetime == "transient") else res.lifetime
        fmt = res.format
        accel = res.accel
        if res.kind == "image":
            size_bytes, extent, mips, layers, samples = None, tuple(res.extent), res.mips, res.layers, res.samples
        else:
            size_bytes, extent, mips, layers, samples = res.bytes, None, None, None, None
        out.append(_Resource(  # positional, in PlanResource's field order (a keyword call costs more)
            name, res.kind, fmt.vk_name if fmt else None, mem.bytes, size_bytes, mem.alignment, mem.memory_type_bits,
            mem.memory_class, mem.usages, lifetime, mem.first, mem.last, heap, offset,
            initial.get(name), final.get(name),
            extent, mips, layers, samples, _frozen_json(accel.as_plan()) if accel is not None else None,
            res.scratch_of,
        ))
    return tuple(out)


def emit(c: Compilation) -> pm.Plan:
    """The plan of a compilation that went through every earlier phase."""
    spec, placement, culling = c.spec, c.placement, c.culling
    assert placement is not None and culling is not None
    passes = _passes(c)
    sync = c.sync
    assert sync is not None
    present = {p.queue for p in c.passes}
    st = placement.stats
    return pm.Plan(
        graph=spec.name, source=spec.source, scene=spec.scene_name, scene_source=c.spec.scene_source,
        size=tuple(spec.size), params=_frozen(spec.params), features=_frozen(spec.features),
        device_profile=c.profile_name, queues=tuple(q for q in pm.QUEUE_ORDER if q in present),
        passes=passes,
        culled=_culled(c),
        dropped_reads=tuple(pm.DroppedRead(d.pass_name, d.resource, d.reason) for d in culling.dropped_reads),
        resources=_resources(c),
        heaps=tuple([_Heap(h.id, h.bytes, h.memory_class, h.alignment) for h in placement.heaps]),
        outputs=tuple(c.spec.outputs),
        stats=pm.Stats(
            barriers=sum(map(len, sync.barriers)), semaphores=sum(sync.signals),
            peak_bytes=st.peak_bytes, lower_bound_bytes=st.lower_bound_bytes, unaliased_bytes=st.unaliased_bytes,
            allocations=st.allocations, policy=st.policy,
            schedule=None if c.schedule == DEFAULT_SCHEDULE else c.schedule,  # absent = declaration order
        ),
    )


def _culled(c: Compilation) -> tuple[pm.Culled, ...]:
    """The culled passes, each with the resources only culled passes used and their bytes
    (``measure`` found them; compiled where built)."""
    if NATIVE is None:
        return _culled_python(c)
    assert c.culling is not None
    return NATIVE.culled(c.culling.culled, c.culled_only, c.culled_bytes)


def _culled_python(c: Compilation) -> tuple[pm.Culled, ...]:
    assert c.culling is not None
    get_only, get_bytes = c.culled_only.get, c.culled_bytes.get
    out = []
    for x in c.culling.culled:
        only = get_only(x.pass_name)
        if only is None:
            out.append(_Culled(x.pass_name, x.reason, (), 0))
        else:
            out.append(_Culled(x.pass_name, x.reason, only, sum(get_bytes(r, 0) for r in only)))
    return tuple(out)
