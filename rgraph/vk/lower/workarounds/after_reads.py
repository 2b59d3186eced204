"""Which plan barriers follow reads of an earlier write, and that write's stages.

The compiler's barrier after reads names the reads' stages and no access: the write before
those reads was made available and visible by the barrier in front of them, and the new
barrier is ordered after the write through the reads (an execution dependency chain).
Khronos validation 1.3.239 loses that chain when the queue waits on a semaphore in between:
the waiting queue imports the other queue's copy of the same write, and its own dependency
chain for the write is replaced by the wait's stages (H100 fuzz, random graph seed 2936 with
17 passes: "storage write on graphics -> barrier -> storage reads -> graphics waits for
compute, which had imported the write -> transition" reported WRITE_AFTER_WRITE against the
write; seed 1 with 22 passes: a persistent buffer's storage write in one frame, indirect and
uniform reads in the next, a wait for compute in between, and the next storage write was
reported WRITE_AFTER_WRITE against the previous frame's). The runtime then names the write
itself in the barrier's src scope (its stages, MEMORY_WRITE): a second availability operation
for a write that is already available, a no-op by the spec, in the form that layer checks
first (``name_read_write`` below).

Only barriers whose latest earlier access to an overlapping subresource is a read count, so
a barrier that lost its src access (a mutation, a generator bug) is never repaired here.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import replace

from rgraph.vk.lower.context import BarrierContext
from rgraph.vk.lower.model import BarrierSpec


def _overlaps(a: dict | None, b: dict | None) -> bool:
    if a is None or b is None:
        return True
    return all(a[k][0] < b[k][1] and b[k][0] < a[k][1] for k in ("mips", "layers") if k in a and k in b)


def _accesses_by_resource(plan: dict) -> dict[str, list[tuple[int, dict]]]:
    """resource -> (pass index, access), in plan order."""
    by_resource: dict[str, list[tuple[int, dict]]] = {}
    for j, q in enumerate(plan["passes"]):
        for a in q["accesses"]:
            by_resource.setdefault(a["resource"], []).append((j, a))
    return by_resource


def writers_before_reads(plan: dict) -> list[dict[int, tuple[str, ...]]]:
    """Per pass, barrier index -> stages of the writes to that resource's overlapping
    subresources (anywhere in the plan, a frame wraps around), for every barrier whose latest
    earlier access (in plan order, else from the previous frame) to an overlapping
    subresource is a read."""
    by_resource = _accesses_by_resource(plan)
    out: list[dict[int, tuple[str, ...]]] = []
    for i, p in enumerate(plan["passes"]):
        found: dict[int, tuple[str, ...]] = {}
        for bi, b in enumerate(p["barriers"]):
            sub = b.get("subresource")
            touching = [(j, a) for j, a in by_resource.get(b["resource"], ())
                        if _overlaps(a.get("subresource"), sub)]
            writes = sorted({s for _j, a in touching if a["write"] for s in a["stages"]})
            before = [a for j, a in touching if j < i] or [a for j, a in touching if j >= i]
            if writes and before and not before[-1]["write"]:
                found[bi] = tuple(writes)
        out.append(found)
    return out


def alias_names(aliases: str | list[str] | None) -> list[str]:
    """A barrier's ``aliases``: one name, a list, or none."""
    return [] if not aliases else [aliases] if isinstance(aliases, str) else list(aliases)


def src_additions(plan: dict, queue_key: Callable[[str], Hashable]) -> list[dict[int, tuple[str, ...]]]:
    """Per pass, barrier index -> stages its src scope also names, for the barriers whose src
    scope relies on an execution chain the 1.3.239 layer can lose:

    - ``writers_before_reads``: the reads' write stages;
    - a first use of aliased memory after the previous occupants' reads (src stages, no src
      access; the latest access of the previous occupants in the frame is a read, so an
      emptied post-write scope, a mutation, is not repaired): their write stages;
    - a barrier whose src is another VkQueue (its layout change after a queue family
      ownership acquire, src = the acquire's dst stages: H100 fuzz 422/25 and 156/32);

    each with the stages of every semaphore wait on another VkQueue (``queue_key``: plan queue
    -> VkQueue) that the barrier's VkQueue makes in the frame (frames repeat, so also those
    after it). Each such wait re-imports the other queue's copy of a write that queue once
    imported or made, and the layer then replaces this queue's dependency chain for the write
    with that wait's stages (H100 fuzz seed 231271/12: a buffer written on compute, read as
    indirect on graphics, two waits for compute later, the next write on graphics reported
    WRITE_AFTER_WRITE; 885/24 aliased: a buffer's first use after its previous occupant's
    uniform reads); a src scope that names those stages chains to it."""
    writers = writers_before_reads(plan)
    waits: dict[Hashable, set[str]] = {}
    for p in plan["passes"]:
        key = queue_key(p["queue"])
        waits.setdefault(key, set()).update(
            s for w in p["waits"] if queue_key(w["queue"]) != key for s in w["stages"])
    by_resource = _accesses_by_resource(plan)
    out: list[dict[int, tuple[str, ...]]] = []
    for i, (p, found) in enumerate(zip(plan["passes"], writers, strict=True)):
        key = queue_key(p["queue"])
        waited = waits.get(key, set())
        extra: dict[int, tuple[str, ...]] = {}
        for bi, b in enumerate(p["barriers"]):
            stages = set(found.get(bi, ()))
            relies = bi in found
            if b["src"]["stages"] and not b["src"]["access"]:
                earlier = [a for _j, a in sorted(((j, a) for name in alias_names(b.get("aliases"))
                                                  for j, a in by_resource.get(name, ()) if j < i),
                                                 key=lambda ja: ja[0])]
                if earlier and not earlier[-1]["write"]:
                    relies = True
                    stages.update(s for a in earlier if a["write"] for s in a["stages"])
                elif _after_reads_from_undefined(b):
                    relies = True
            if b["src"]["stages"] and queue_key(b["src"]["queue"]) != key:
                relies = True
            if relies and (stages or waited):
                extra[bi] = tuple(sorted(stages | waited))
        out.append(extra)
    return out


def _after_reads_from_undefined(barrier: dict) -> bool:
    """A first use from UNDEFINED ordered after reads (aliased memory: the previous occupant's
    last reads; H100 fuzz seed 0/28 aliased: the layer, which tracks that memory here, had
    replaced its chain for the previous occupant's write with the last wait's stages)."""
    src = barrier["src"]
    return src["layout"] == "UNDEFINED" and bool(src["stages"]) and not src["access"]


# ----------------------------------------------------------------- the rewrites (per struct)

#: srcAccessMask of a layout transition that follows reads (see ``memory_read_after_reads``);
#: with the write those reads read, when it is known (``name_read_write``).
AFTER_READS_ACCESS = ("MEMORY_READ",)
AFTER_WRITE_READS_ACCESS = ("MEMORY_READ", "MEMORY_WRITE")


def _is_transition_after_reads(spec: BarrierSpec) -> bool:
    return (spec.old_layout is not None and spec.old_layout != spec.new_layout and bool(spec.src_stages)
            and not spec.src_access)


def name_read_write(spec: BarrierSpec, ctx: BarrierContext) -> list[BarrierSpec]:
    """An ordinary barrier after reads (src stages, no src access) whose reads read a write
    with stages ``ctx.write_stages`` (``src_additions``, which says why the 1.3.239 layer
    needs it) also names that write in its src scope: its stages and MEMORY_READ|MEMORY_WRITE
    (a repeated availability operation for a write already available, a no-op by the spec).
    Layout transitions and buffer or same-layout barriers before a write alike. A transition
    from UNDEFINED (aliased memory after the previous occupant's reads) gets the stages only
    (``memory_read_after_reads`` names MEMORY_READ); ownership transfers keep their
    spec-mandated masks."""
    write_stages = ctx.write_stages
    if (write_stages and spec.src_stages and not spec.src_access and spec.src_family is None
            and spec.dst_family is None):
        stages = tuple(sorted(set(spec.src_stages) | set(write_stages)))
        if spec.old_layout == "UNDEFINED":
            return [replace(spec, src_stages=stages)]
        return [replace(spec, src_stages=stages, src_access=AFTER_WRITE_READS_ACCESS)]
    return [spec]


def memory_read_after_reads(spec: BarrierSpec, ctx: BarrierContext) -> list[BarrierSpec]:
    """A layout transition whose src scope is reads only (src stages, no src access) gets
    srcAccessMask MEMORY_READ. By the spec this is a no-op: availability operations concern
    writes, the write before those reads was made available by the barrier in front of them,
    and the transition is ordered after it through the reads' stages (an execution chain).
    The 1.3.239 layer credits that chain inside one command buffer but not at submit time
    across command buffers: there it wants the transition's src access scope to meet the
    accesses the write was made visible to (the reads), and otherwise reports
    WRITE_AFTER_WRITE for "storage write -> (barrier, no layout change) -> storage read ->
    transition" (random graphs seed 0 and 9, tests/vk/test_run_fuzz.py), and likewise for an
    aliased resource's first transition (from UNDEFINED) after the previous occupant's reads
    (seeds 0 and 32 with 10 passes, aliased). Naming the reads in srcAccessMask records the
    same dependency in the form the layer understands. Applied after fitting the barrier to
    the queue family, so that a src scope left without accesses there gets it too. From
    UNDEFINED even with a src access: aliased memory whose previous occupants ended with
    reads and with writes (seed 0/32 aliased, lavapipe and H100) names the reads too."""
    if (_is_transition_after_reads(spec) or (spec.old_layout == "UNDEFINED" and spec.src_stages)) \
            and "MEMORY_READ" not in spec.src_access:
        return [replace(spec, src_access=tuple(sorted({*spec.src_access, *AFTER_READS_ACCESS})))]
    return [spec]
