"""The compiler's phases: one ``Compilation`` value through a visible list of pure functions.

    PHASES = cull -> schedule -> size_accels -> trace -> measure -> place -> synchronize -> emit

Each phase takes a ``Compilation`` and returns a new one with its fields filled in
(``dataclasses.replace``); none mutates its input or the ``Spec``. Only ``measure`` calls
out, to the memory-requirements provider (a device profile or a live device).

networkx: ``Compilation.graph`` is the dependency DAG of the scheduled passes
(``rgraph.ir.graph.build_graph``), built on demand for views and tests; ``--schedule
async-early`` orders passes with ``networkx.lexicographical_topological_sort`` on it
(``rgraph.ir.schedule``). The default path does without it: dependencies are found in
program order, so every edge points forward and declaration order already *is* the
lexicographic topological order keyed by declaration index; culling is one backwards
walk over the cells still waiting for their producer (``rgraph.ir.cull._alive``; it
builds no edges). Building a DiGraph for either costs more than the phase itself
(benchmarks/compile_scaling.py).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING

from rgraph.compiler import memory
from rgraph.compiler import sync as sync_python
from rgraph.compiler.emit import emit as emit_plan
from rgraph.compiler.queue_order import cross_queue_conflicts
from rgraph.compiler.sync import SyncResult
from rgraph.compiler.trace import Trace
from rgraph.compiler.trace import trace as trace_passes
from rgraph.defaults import DEFAULT_SCHEDULE
from rgraph.errors import RGraphError
from rgraph.ir.cull import Culled, Culling
from rgraph.ir.cull import cull as cull_spec
from rgraph.ir.schedule import schedule_passes
from rgraph.memory.model import Placement
from rgraph.native import load
from rgraph.spec.specialize import PassSpec, Spec

#: ``rgraph/compiler/sync.py`` compiled as it is (setup.py ``TWINS``, typed by ``_sync.pxd``),
#: None where not built or ``RGRAPH_NATIVE=0``: then sync.py itself runs.
SYNC_NATIVE = load("rgraph.compiler._sync")

if TYPE_CHECKING:
    import networkx as nx

    from rgraph.compiler.memory import MemoryRequirementsProvider
    from rgraph.plan.model import Plan


@dataclass(frozen=True)
class Compilation:
    """Inputs of a compile and the results of every phase run so far (None: not yet)."""

    spec: Spec
    policy: str
    provider: MemoryRequirementsProvider
    profile_name: str
    schedule: str = DEFAULT_SCHEDULE  # rgraph.ir.schedule mode (``--schedule``)
    culling: Culling | None = None
    passes: tuple[PassSpec, ...] = ()  # scheduled (executed) order
    trace: Trace | None = None  # scopes, usages, lifetimes and cell timelines of ``passes``
    memory: Mapping[str, memory.ResourceMemory] = field(default_factory=dict)  # used resources, name order
    culled_bytes: Mapping[str, int] = field(default_factory=dict)  # resources only culled passes use
    culled_only: Mapping[str, tuple[str, ...]] = field(default_factory=dict)  # culled pass -> those it uses (if any)
    placement: Placement | None = None
    aliases: Mapping[str, list[str]] = field(default_factory=dict)  # resource -> earlier occupants it waits for
    sync: SyncResult | None = None
    plan: Plan | None = None

    @cached_property
    def graph(self) -> nx.DiGraph:
        """The dependency DAG of the scheduled passes (node attribute ``order``)."""
        from rgraph.ir.graph import build_graph

        return build_graph(self.passes)


def cull(c: Compilation) -> Compilation:
    """Drop passes whose results reach no output and reads with no producer."""
    return replace(c, culling=cull_spec(c.spec))


def schedule(c: Compilation) -> Compilation:
    """Executed order of the kept passes (``rgraph.ir.schedule``; default: declaration order)."""
    assert c.culling is not None
    return replace(c, passes=tuple(schedule_passes(c.culling.passes, c.schedule)))


def size_accels(c: Compilation) -> Compilation:
    """Accels sized on the provider (``rgraph.compiler.accel``): a new ``Spec`` whose
    resources hold each used accel's layout and its build scratch buffer; build passes
    also write the scratch (refits read the accel)."""
    from rgraph.compiler.accel import size_accels as size

    for r in c.spec.resources.values():  # (a loop: a generator's resumptions cost more)
        if r.kind == "accel":
            break
    else:
        return replace(c)
    spec = replace(c.spec, resources=dict(c.spec.resources))
    kept = list(c.passes)
    passes = size(spec, kept, c.provider)
    if c.culling is not None and c.culling.culled:
        from rgraph.compiler.accel import size_culled_accels

        names = {x.pass_name for x in c.culling.culled}
        size_culled_accels(spec, kept, [p for p in spec.passes if p.name in names], c.provider)
    return replace(c, spec=spec, passes=tuple(passes))


def trace(c: Compilation) -> Compilation:
    """One walk over the executed accesses (``rgraph.compiler.trace``): each access's sync2
    scope, each resource's usages and lifetime, each cell's timeline, the cross-queue waits."""
    return replace(c, trace=trace_passes(c.passes, c.spec.resources))


def measure(c: Compilation) -> Compilation:
    """Sizes, alignments and memory classes of the used resources (and of culled-only ones).
    Compiled where built (``memory.NATIVE.measure``: the same values as :func:`_measure_python`)."""
    assert c.culling is not None and c.trace is not None
    spec = c.spec
    if memory.NATIVE is None:
        used_memory, culled_bytes, culled_only = _measure_python(c)
    else:
        used_memory, culled_bytes, culled_only = memory.NATIVE.measure(
            spec.resources, c.trace.resources, spec.outputs, c.provider, c.culling.culled, spec.passes, spec.empty,
            memory._SAME_BUFFER_FLAG)
    return replace(c, memory=used_memory, culled_bytes=culled_bytes, culled_only=culled_only)


def _measure_python(c: Compilation) -> tuple[dict[str, memory.ResourceMemory], dict[str, int],
                                             dict[str, tuple[str, ...]]]:
    """``measure``'s ``(memory, culled_bytes, culled_only)``: the Python reference (and the
    path where ``rgraph/compiler/_memory.pyx`` is not built)."""
    assert c.culling is not None and c.trace is not None
    spec = c.spec
    traced = c.trace.resources
    used = {name: r.usages for name, r in traced.items()}
    spans = {name: (r.first, r.last) for name, r in traced.items()}
    reqs = memory.requirements_python(spec.resources, used, spec.outputs, c.provider)
    culled_only, culled_passes = _culled_only_python(spec, c.culling.culled, traced)
    culled_used = memory.usages_by_resource(culled_passes) if culled_passes else {}
    culled_used = {r: u for r, u in culled_used.items() if r not in traced}
    culled_reqs = memory.requirements_python(spec.resources, culled_used, spec.outputs, c.provider) if culled_used else {}
    return (memory.resource_memory_python(reqs, used, spans),
            {r: 0 if r in spec.empty else q.bytes for r, q in culled_reqs.items()}, culled_only)


def _culled_only(spec: Spec, culled: Sequence[Culled], traced: Mapping[str, object]
                 ) -> tuple[dict[str, tuple[str, ...]], list[PassSpec]]:
    """Per culled pass that uses resources no executed pass uses (not in ``traced``): those,
    sorted; and those passes (the only ones whose usages size a culled-only resource).
    Compiled where built (``memory.NATIVE``)."""
    if memory.NATIVE is None:
        return _culled_only_python(spec, culled, traced)
    return memory.NATIVE.culled_only(spec.passes, culled, traced)


def _culled_only_python(spec: Spec, culled: Sequence[Culled], traced: Mapping[str, object]
                        ) -> tuple[dict[str, tuple[str, ...]], list[PassSpec]]:
    if not culled:
        return {}, []
    by_name = {p.name: p for p in spec.passes}
    only_by_pass: dict[str, tuple[str, ...]] = {}
    passes: list[PassSpec] = []
    for x in culled:
        p = by_name[x.pass_name]
        only: set[str] | None = None
        for a in p.accesses:
            if a.resource not in traced:
                if only is None:
                    only = {a.resource}
                else:
                    only.add(a.resource)
        if only is not None:  # most culled passes: every resource is also used by an executed one
            only_by_pass[p.name] = tuple(sorted(only))
            passes.append(p)
    return only_by_pass, passes


def place(c: Compilation) -> Compilation:
    """Heaps and offsets: transients by the allocator policy (may alias), others dedicated."""
    try:
        resources = c.spec.resources
        assert c.trace is not None
        if memory.NATIVE is None:
            aliasable = [n for n in c.memory if resources[n].lifetime == "transient"]
            split = None
        else:  # the same list, and place_resources' split, in one pass
            aliasable, kept_apart, rest = memory.NATIVE.split_transients(resources, c.memory, c.spec.outputs)
            split = (kept_apart, rest)
        conflicts = cross_queue_conflicts(c.passes, c.trace, aliasable)
        placement = memory.place_resources(resources, c.memory, c.policy, c.spec.outputs, conflicts, split)
    except ValueError as exc:
        raise RGraphError.in_file("<command line>", f"--policy: {exc}") from None
    return replace(c, placement=placement, aliases=memory.alias_sources(placement, c.memory))


def synchronize(c: Compilation) -> Compilation:
    """Barriers, queue-ownership releases, semaphore waits and signals per pass."""
    assert c.placement is not None and c.trace is not None
    offsets, aliases = c.placement.offsets, c.aliases
    # (heap, first byte, end byte) of the resources that alias or are aliased (``with_partial_handoffs``)
    named = {n for preds in aliases.values() for n in preds}.union(aliases)
    ranges = {n: (heap, off, off + c.memory[n].bytes) for n in named for heap, off in (offsets[n],)}
    outputs = set(c.spec.outputs)
    result = None
    whole = sync_python._WALK  # the whole phase compiled (``_sync_walk.synchronize``); None: declined
    if whole is not None:
        result = whole.synchronize(c.passes, c.spec.resources, c.trace, aliases, ranges, outputs)
    if result is None:
        synchronize_passes = (SYNC_NATIVE or sync_python).synchronize
        result = synchronize_passes(c.passes, c.spec.resources, c.trace, aliases, ranges, outputs)
    return replace(c, sync=result)


def emit(c: Compilation) -> Compilation:
    """The typed plan (``rgraph.plan.model.Plan``)."""
    return replace(c, plan=emit_plan(c))


Phase = Callable[[Compilation], Compilation]
PHASES: tuple[tuple[str, Phase], ...] = (
    ("cull", cull), ("schedule", schedule), ("size_accels", size_accels), ("trace", trace),
    ("measure", measure), ("place", place),
    ("synchronize", synchronize), ("emit", emit),
)


def run_phases(c: Compilation, phases: tuple[tuple[str, Phase], ...] = PHASES) -> Compilation:
    for _name, phase in phases:
        c = phase(c)
    return c
