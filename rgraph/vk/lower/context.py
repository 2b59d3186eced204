"""What a barrier rewrite knows about the struct it rewrites (``rgraph.vk.lower.barriers``)."""

from __future__ import annotations

from dataclasses import dataclass

from rgraph.stages import CAPABILITIES


@dataclass(frozen=True)
class BarrierContext:
    """``index``: the plan barrier's index in its pass list; ``group``: 0 for the first
    vkCmdPipelineBarrier2 of the list, 1 for the layout changes after ownership acquires;
    ``wait_stages``: stages of the pass's semaphore waits on another VkQueue (barriers only);
    ``capabilities``: the recording queue family's; ``write_stages``: the extra src stages
    ``workarounds.after_reads.src_additions`` found for this barrier; ``partial_handoff``:
    the hand-off is one the 1.3.239 layer sees only in part (``workarounds.packed_ranges``)."""

    index: int
    group: int
    wait_stages: tuple[str, ...] = ()
    capabilities: frozenset[str] = CAPABILITIES
    write_stages: tuple[str, ...] = ()
    partial_handoff: bool = False
