"""What the runtime will record, as plain data (no Vulkan): the output of ``rgraph.vk.lower``.

Stages, accesses and layouts are plan names (sync2 without prefixes and ``_BIT``); queue
families are indices of the ``QueueLayout`` the plan was lowered for. ``rgraph.vk.record``
turns a ``BarrierCall`` into one vkCmdPipelineBarrier2; the runtime records the calls of a
pass around the pass's own commands and submits the batches in ``order``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class BarrierSpec:
    """One VkImageMemoryBarrier2 / VkBufferMemoryBarrier2 in plan names (pure data, no Vulkan);
    with ``resource`` None, a global VkMemoryBarrier2 (``workarounds.packed_ranges``).

    ``src_family``/``dst_family``: a queue family index, or None for VK_QUEUE_FAMILY_IGNORED.
    ``aspect_layout``: the layout that picks the image aspect (the plan barrier's dst layout,
    else its src layout), so that every struct derived from one plan barrier names one aspect.
    """

    resource: str | None
    subresource: dict | None
    src_stages: tuple[str, ...]
    src_access: tuple[str, ...]
    dst_stages: tuple[str, ...]
    dst_access: tuple[str, ...]
    old_layout: str | None
    new_layout: str | None
    src_family: int | None = None
    dst_family: int | None = None
    aspect_layout: str | None = None

    @property
    def kind(self) -> str:
        if self.resource is None:
            return "memory"
        return "image" if self.old_layout is not None or self.new_layout is not None else "buffer"


#: One vkCmdPipelineBarrier2: its structs are not ordered with each other; consecutive calls are.
BarrierCall = tuple[BarrierSpec, ...]


@dataclass(frozen=True)
class PassRecording:
    """A pass's barrier calls: ``before`` its commands (plan ``barriers``), ``after`` (``releases``)."""

    index: int
    name: str
    queue: str
    before: tuple[BarrierCall, ...]
    after: tuple[BarrierCall, ...]


@dataclass(frozen=True)
class Batch:
    """Passes (plan indices) recorded into one command buffer and submitted as one VkSubmitInfo2."""

    queue: str  # plan queue of the first pass (all passes share its VkQueue)
    passes: tuple[int, ...]


@dataclass(frozen=True)
class SemaphoreEdge:
    """One timeline semaphore of a frame (``rgraph.vk.lower.semaphores``); stages are plan names."""

    signal_batch: int
    wait_batch: int
    signal_stages: Any  # frozenset of stage names (ints in the pure edge tests)
    wait_stages: Any
    frame_edge: bool  # signalled at the end of one frame, waited at the start of the next


@dataclass(frozen=True)
class Recording:
    """Everything recorded and submitted for a plan, computed once (``rgraph.vk.lower.lower``).

    ``plan`` is the plan the runtime executes: the input after the plan-level rewrites
    (``workarounds``), used for initialisation and readback too. ``first_frame`` holds the
    ownership releases recorded once before frame 0 (by releasing queue). ``layer_edges``
    counts semaphore edges added only for the 1.3.239 layer (``workarounds.layer_races``).
    """

    plan: dict
    queues: Any  # rgraph.vk.lower.queues.QueueLayout
    passes: tuple[PassRecording, ...]
    batches: tuple[Batch, ...]
    edges: tuple[SemaphoreEdge, ...]
    order: tuple[int, ...]
    first_frame: dict[str, tuple[BarrierCall, ...]] = field(default_factory=dict)
    layer_edges: int = 0
    workarounds: tuple[str, ...] = ()

    def calls(self) -> int:
        """Number of vkCmdPipelineBarrier2 calls per frame."""
        return sum(len(p.before) + len(p.after) for p in self.passes)
