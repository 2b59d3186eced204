"""Cross-queue semaphores of a frame: one timeline semaphore per edge, signalled and waited
once per frame.

The plan orders queues with per-queue timeline values (pass ``waits``/``signals``). The
runtime turns each cross-VkQueue wait into an edge from the batch that signals the value to
the batch that waits for it, keeps only the latest signalling batch per (waiting batch,
signalling VkQueue) (queue order covers the earlier ones), and adds frame edges: every
VkQueue's first batch of a frame waits for every other VkQueue's last batch of the previous
frame (persistent resources, and memory reused across frames in flight).

Each edge has its own semaphore (a frame edge one per frame-in-flight set), so in host
submission order every semaphore alternates signal, wait, signal, wait. Timeline semantics
need none of this, but Khronos validation 1.3.239 models timeline semaphores as binary: a
signal of a semaphore whose previous signal no wait has consumed is dropped, and the next
wait imports the stale one (false cross-queue races on an H100 when one semaphore per queue
carried every signal of a frame). Alternating semaphores make the layer's pairing exact.

Values: an in-frame edge is signalled and waited with ``frame + 1``; a frame edge of set
``s`` is signalled with ``frame + 1`` at the end of a frame of set ``s`` and waited with
``frame`` (the previous frame's signal, on the previous set's semaphore) at the start of the
next frame; frame 0 waits for value 0, which every timeline starts at.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable
from dataclasses import dataclass
from typing import Any

from rgraph.vk.lower.model import SemaphoreEdge


@dataclass(frozen=True)
class BatchSync:
    """What the lowering knows of one batch: its plan queue, the VkQueue it runs on, the plan
    waits of its first pass and the plan signals of its last pass as (plan queue, value,
    stages: a frozenset of stage names, or an int mask), and the resources its passes access
    or transition (for ``workarounds.layer_races``)."""

    plan_queue: str
    vk_queue: Hashable
    waits: tuple[tuple[str, int, Any], ...]
    signals: tuple[tuple[str, int, Any], ...]
    resources: frozenset[str] = frozenset()


@dataclass(frozen=True)
class SemaphoreUse:
    """One VkSemaphoreSubmitInfo of a batch: semaphore index, value = frame + offset, stages."""

    semaphore: int
    offset: int
    stages: Any


def semaphore_edges(batches: list[BatchSync], all_commands: Any,
                    extra: Iterable[tuple[int, int]] = ()) -> list[SemaphoreEdge]:
    """The edges of one frame (see the module docstring); ``all_commands`` is the stage mask
    of frame edges and of ``extra`` in-frame edges (signal batch, wait batch) that the plan
    does not need (``workarounds.layer_races`` adds them; they merge like plan waits). Stage
    sets merge with ``|`` (frozensets of names, or int masks)."""
    none = type(all_commands)()
    signalled_by: dict[tuple[str, int], int] = {}
    for bi, batch in enumerate(batches):
        for queue, value, _stages in batch.signals:
            signalled_by[(queue, value)] = bi
    latest: dict[tuple[int, Hashable], tuple[int, int, int]] = {}  # (wait batch, signal VkQueue) -> edge parts
    for bi, batch in enumerate(batches):
        for queue, value, stages in batch.waits:
            if (queue, value) not in signalled_by:
                raise ValueError(f"batch {bi} waits for {queue} value {value}, which no pass signals")
            source = signalled_by[(queue, value)]
            if batches[source].vk_queue == batch.vk_queue:
                continue  # submission order and the plan's barriers order one VkQueue
            if source >= bi:
                raise ValueError(f"batch {bi} waits for batch {source}, which comes later in the plan")
            key = (bi, batches[source].vk_queue)
            signal_stages = _signal_stages(batches[source], queue, value)
            if key in latest:
                prev_source, prev_signal, prev_wait = latest[key]
                source, signal_stages, stages = max(source, prev_source), signal_stages | prev_signal, stages | prev_wait
            latest[key] = (source, signal_stages, stages)
    for source, bi in extra:
        key = (bi, batches[source].vk_queue)
        prev_source, prev_signal, prev_wait = latest.get(key, (source, none, none))
        latest[key] = (max(source, prev_source), prev_signal | all_commands, prev_wait | all_commands)
    edges = [SemaphoreEdge(source, wait, signal_stages, wait_stages, False)
             for (wait, _q), (source, signal_stages, wait_stages) in sorted(latest.items(), key=lambda kv: kv[0][0])]
    first: dict[Hashable, int] = {}
    last: dict[Hashable, int] = {}
    for bi, batch in enumerate(batches):
        first.setdefault(batch.vk_queue, bi)
        last[batch.vk_queue] = bi
    for x, last_x in last.items():
        for y, first_y in first.items():
            if x != y:
                edges.append(SemaphoreEdge(last_x, first_y, all_commands, all_commands, True))
    return edges


def _signal_stages(batch: BatchSync, queue: str, value: int) -> Any:
    return next(stages for q, v, stages in batch.signals if (q, v) == (queue, value))


def semaphore_count(edges: list[SemaphoreEdge], sets: int) -> int:
    return sum(sets if e.frame_edge else 1 for e in edges)


def batch_semaphores(edges: list[SemaphoreEdge], sets: int, s: int,
                     batch: int) -> tuple[list[SemaphoreUse], list[SemaphoreUse]]:
    """(waits, signals) of ``batch`` in the submits of frame-in-flight set ``s``."""
    waits: list[SemaphoreUse] = []
    signals: list[SemaphoreUse] = []
    index = 0
    for e in edges:
        if e.frame_edge:
            if e.signal_batch == batch:
                signals.append(SemaphoreUse(index + s, 1, e.signal_stages))
            if e.wait_batch == batch:
                waits.append(SemaphoreUse(index + (s - 1) % sets, 0, e.wait_stages))
            index += sets
        else:
            if e.signal_batch == batch:
                signals.append(SemaphoreUse(index, 1, e.signal_stages))
            if e.wait_batch == batch:
                waits.append(SemaphoreUse(index, 1, e.wait_stages))
            index += 1
    return waits, signals


def submission_order(batches: list[BatchSync], edges: list[SemaphoreEdge]) -> list[int]:
    """Host submission order of a frame's batches: each VkQueue runs ahead as far as its waits
    allow before another queue's batch is submitted (queue order and signal-before-wait kept).

    Khronos validation 1.3.239 checks a batch for races against every other queue's last
    batch it has not waited for, and counts in that batch's context the accesses it imported
    from this very queue: a graphics pass submitted after a compute batch that waited for
    graphics, and before graphics waits for it, was reported as racing its own queue's earlier
    accesses (H100: the IBL passes against the previous frame's forward). Running ahead
    submits such passes before the other queue's batch exists.
    """
    needs: dict[int, set[int]] = {}
    for e in edges:
        if not e.frame_edge:
            needs.setdefault(e.wait_batch, set()).add(e.signal_batch)
    pending: dict[Hashable, list[int]] = {}
    for bi, batch in enumerate(batches):
        pending.setdefault(batch.vk_queue, []).append(bi)
    order: list[int] = []
    done: set[int] = set()
    current: Hashable | None = None
    while len(order) < len(batches):
        ready = [q[0] for q in pending.values() if q and needs.get(q[0], set()) <= done]
        if not ready:
            raise ValueError("the batches' semaphore waits form a cycle")
        same = [bi for bi in ready if batches[bi].vk_queue == current]
        bi = same[0] if same else min(ready)
        current = batches[bi].vk_queue
        pending[current].pop(0)
        order.append(bi)
        done.add(bi)
    return order
