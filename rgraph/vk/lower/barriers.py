"""Plan barriers -> the vkCmdPipelineBarrier2 calls that execute them, as ``BarrierSpec`` data.

``split`` turns one plan barrier into its structs (the Vulkan form of ownership transfers);
then every struct goes through ``REWRITES``, a named ordered list: two are what the spec
requires on the recording queue (``chain_to_waits``, ``fit_to_queue_family``), the others
are the validation-layer 1.3.239 workarounds of ``rgraph.vk.lower.workarounds``, each of
which can be switched off by name.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence, Set
from dataclasses import dataclass, replace

from rgraph.stages import CAPABILITIES, fit_to_queue
from rgraph.vk.lower.context import BarrierContext
from rgraph.vk.lower.model import BarrierSpec
from rgraph.vk.lower.workarounds import after_reads, packed_ranges


def chain_to_waits(spec: BarrierSpec, ctx: BarrierContext) -> list[BarrierSpec]:
    """Every barrier before the pass with a src scope adds the stages of the pass's semaphore
    waits on another VkQueue to its src stages, so it chains to the wait: a plan barrier's src
    stages may name another queue's stages (an aliased resource's previous occupant read on
    the compute queue, say), which on this queue are ordered after nothing the semaphore
    covers (an H100 run: WRITE_AFTER_READ in forward)."""
    if ctx.wait_stages and ctx.group == 0 and spec.src_stages and spec.src_family is None:
        return [replace(spec, src_stages=tuple(sorted(set(spec.src_stages) | set(ctx.wait_stages))))]
    return [spec]


def fit_to_queue_family(spec: BarrierSpec, ctx: BarrierContext) -> list[BarrierSpec]:
    """Stages the recording queue's family does not run, and the accesses only they perform,
    are dropped from both scopes (``rgraph.stages.fit_to_queue``): a release on a compute-only
    family after reads on the graphics queue names INDEX_INPUT in the plan, which that family
    rejects (VUID-vkCmdPipelineBarrier2-srcStageMask-03849, H100 fuzz seed 48)."""
    if ctx.capabilities == CAPABILITIES:
        return [spec]
    src_stages, src_access = fit_to_queue(spec.src_stages, spec.src_access, ctx.capabilities)
    dst_stages, dst_access = fit_to_queue(spec.dst_stages, spec.dst_access, ctx.capabilities)
    return [replace(spec, src_stages=src_stages, src_access=src_access, dst_stages=dst_stages,
                    dst_access=dst_access)]


@dataclass(frozen=True)
class Rewrite:
    name: str
    layer: bool  # a validation-layer workaround (switchable), else required by the spec
    apply: Callable[[BarrierSpec, BarrierContext], list[BarrierSpec]]


#: Applied to every struct in this order.
REWRITES: tuple[Rewrite, ...] = (
    Rewrite("chain_to_waits", False, chain_to_waits),
    Rewrite("name_read_write", True, after_reads.name_read_write),
    Rewrite("fit_to_queue_family", False, fit_to_queue_family),
    Rewrite("memory_read_after_reads", True, after_reads.memory_read_after_reads),
    Rewrite("packed_range_global_barrier", True, packed_ranges.global_after),
)


def split(b: dict, role: str, families: Mapping[str, int]) -> list[tuple[int, BarrierSpec]]:
    """(call index, struct) pairs for one plan barrier, before any rewrite.

    ``role`` is "barrier" (before the pass) or "release" (after it).

    - Ordinary barriers (one queue) are one struct each, queue families IGNORED.
    - An ownership pair whose two plan queues share a family: the release is skipped and the
      acquire point executes one ordinary barrier (the semaphore orders the queues).
    - A queue-family ownership transfer between distinct families carries NO layout change:
      the release (source queue) and the acquire (destination queue) both keep the source
      layout (oldLayout == newLayout), and the layout change is a separate ordinary barrier
      recorded on the destination queue right after the acquire (a second call, its src scope
      the acquire's dst stages, so the two chain). The acquire's src stages are its own dst
      stages: they are the stages the pass's semaphore wait covers (the plan's wait stages hold
      every stage of the pass's accesses that wait for another queue), so the acquire chains to
      the wait and happens after the release. With src stages NONE (as before) the acquire and
      its layout transition were ordered after nothing on the destination queue: syncval
      reported the acquire's transition racing the release's (WRITE_RACING_WRITE), the reads
      after it racing the release (READ_RACING_WRITE), and the acquire's transition racing the
      previous frame's reads on the destination queue (WRITE_AFTER_READ). Keeping the layout
      out of the pair also keeps a layer that does not model ownership transfers (1.3.239,
      DESIGN.md) from counting one transition twice; release/acquire access masks follow the
      spec (release: no dst access, acquire: no src access).
    """
    src, dst = b["src"], b["dst"]
    resource, sub = b["resource"], b.get("subresource")
    crossing = src["queue"] != dst["queue"]
    transfer = crossing and families[src["queue"]] != families[dst["queue"]]
    aspect = dst["layout"] if dst["layout"] not in (None, "UNDEFINED") else src["layout"]
    src_stages, src_access = tuple(src["stages"]), tuple(src["access"])
    dst_stages, dst_access = tuple(dst["stages"]), tuple(dst["access"])
    if not transfer:
        if crossing and role == "release":
            return []  # same family: executed once, at the acquire point
        return [(0, BarrierSpec(resource, sub, src_stages, src_access, dst_stages, dst_access, src["layout"],
                                dst["layout"], None, None, aspect))]
    pair = (families[src["queue"]], families[dst["queue"]])
    held = src["layout"]  # the layout the resource keeps while it changes hands
    if role == "release":
        return [(0, BarrierSpec(resource, sub, src_stages, src_access, (), (), held, held, *pair, aspect))]
    out = [(0, BarrierSpec(resource, sub, dst_stages, (), dst_stages, dst_access, held, held, *pair, aspect))]
    if src["layout"] != dst["layout"]:
        out.append((1, BarrierSpec(resource, sub, dst_stages, (), dst_stages, dst_access, src["layout"], dst["layout"],
                                   None, None, aspect)))
    return out


def lower_barriers(barriers: list[dict], role: str, families: Mapping[str, int],
                   wait_stages: Sequence[str] = (),
                   capabilities: frozenset[str] = CAPABILITIES,
                   writers: Mapping[int, tuple[str, ...]] | None = None,
                   partial_handoffs: Set[int] = frozenset(),
                   disabled: Collection[str] = ()) -> list[list[BarrierSpec]]:
    """Plan barriers -> vkCmdPipelineBarrier2 calls in recording order (see ``split``), each
    struct rewritten by ``REWRITES`` except those named in ``disabled``.

    ``families`` maps plan queues to queue family indices; ``wait_stages``: the stages of the
    pass's semaphore waits on another VkQueue; ``capabilities``: what the recording queue's
    family does; ``writers``: barrier index -> extra src stages
    (``workarounds.after_reads.src_additions``); ``partial_handoffs``: indices of hand-offs
    the 1.3.239 layer sees in part (``workarounds.packed_ranges.partial_handoffs``). Each
    call is a list of structs (not ordered with each other; consecutive calls are).
    """
    rewrites = [r for r in REWRITES if r.name not in disabled]
    groups: tuple[list[BarrierSpec], list[BarrierSpec]] = ([], [])
    chain = tuple(sorted(set(wait_stages)))
    for index, b in enumerate(barriers):
        for group, spec in split(b, role, families):
            ctx = BarrierContext(index, group, chain, capabilities, (writers or {}).get(index, ()),
                                 index in partial_handoffs)
            specs = [spec]
            for rewrite in rewrites:
                specs = [out for s in specs for out in rewrite.apply(s, ctx)]
            groups[group].extend(specs)
    return [group for group in groups if group]
