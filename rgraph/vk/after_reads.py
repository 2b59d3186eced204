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
first (``rgraph.vk.record``).

Only barriers whose latest earlier access to an overlapping subresource is a read count, so
a barrier that lost its src access (a mutation, a generator bug) is never repaired here.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable


def _overlaps(a: dict | None, b: dict | None) -> bool:
    if a is None or b is None:
        return True
    return all(a[k][0] < b[k][1] and b[k][0] < a[k][1] for k in ("mips", "layers") if k in a and k in b)


def writers_before_reads(plan: dict) -> list[dict[int, tuple[str, ...]]]:
    """Per pass, barrier index -> stages of the writes to that resource's overlapping
    subresources (anywhere in the plan, a frame wraps around), for every barrier whose latest
    earlier access (in plan order, else from the previous frame) to an overlapping
    subresource is a read."""
    by_resource: dict[str, list[tuple[int, dict]]] = {}  # resource -> (pass index, access), plan order
    for j, q in enumerate(plan["passes"]):
        for a in q["accesses"]:
            by_resource.setdefault(a["resource"], []).append((j, a))
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


def src_additions(plan: dict, queue_key: Callable[[str], Hashable]) -> list[dict[int, tuple[str, ...]]]:
    """``writers_before_reads`` plus, for each such barrier, the stages of every semaphore wait
    on another VkQueue (``queue_key``: plan queue -> VkQueue) made so far in the frame on the
    barrier's VkQueue. Each such wait re-imports the other queue's copy of a write that queue
    once imported or made, and the 1.3.239 layer then replaces this queue's dependency chain
    for the write with that wait's stages (H100 fuzz seed 231271/12: a buffer written on
    compute, read as indirect on graphics, two waits for compute later, the next write on
    graphics reported WRITE_AFTER_WRITE); a src scope that names those stages chains to it."""
    writers = writers_before_reads(plan)
    imported: dict[Hashable, set[str]] = {}
    out: list[dict[int, tuple[str, ...]]] = []
    for p, found in zip(plan["passes"], writers, strict=True):
        key = queue_key(p["queue"])
        waited = imported.setdefault(key, set())
        waited.update(s for w in p["waits"] if queue_key(w["queue"]) != key for s in w["stages"])
        extra = {bi: tuple(sorted(set(found.get(bi, ())) | waited)) for bi, b in enumerate(p["barriers"])
                 if bi in found or (_after_reads_from_undefined(b) and waited)}
        out.append(extra)
    return out


def _after_reads_from_undefined(barrier: dict) -> bool:
    """A first use from UNDEFINED ordered after reads (aliased memory: the previous occupant's
    last reads; H100 fuzz seed 0/28 aliased: the layer, which tracks that memory here, had
    replaced its chain for the previous occupant's write with the last wait's stages)."""
    src = barrier["src"]
    return src["layout"] == "UNDEFINED" and bool(src["stages"]) and not src["access"]
