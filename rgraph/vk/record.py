"""Lowered barrier calls (``rgraph.vk.lower.Recording``) as sync2 structs: nothing here
decides a barrier, ``rgraph.vk.lower`` did. (``RecordContext``, what pass implementations
record with, is ``rgraph.vk.record_context``; the name stays importable from here.)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from rgraph.vk import names
from rgraph.vk.loader import vk
from rgraph.vk.lower.model import BarrierCall, BarrierSpec
from rgraph.vk.record_context import RecordContext
from rgraph.vk.resources import ResourceSet

__all__ = ["BarrierBatch", "RecordContext", "barrier_batches"]


def _aspect_for_layout(format_name: str, layout: str) -> int:
    v = vk()
    if layout.startswith("DEPTH_") and not layout.startswith("DEPTH_STENCIL") and "STENCIL" not in layout:
        return v.VK_IMAGE_ASPECT_DEPTH_BIT
    if layout.startswith("STENCIL_"):
        return v.VK_IMAGE_ASPECT_STENCIL_BIT
    return names.aspect_mask(format_name)


@dataclass
class BarrierBatch:
    """One vkCmdPipelineBarrier2's structs, kept alive until recorded."""

    dependency: Any
    keep: list[Any] = field(default_factory=list)
    count: int = 0


def barrier_batches(resources: ResourceSet, set_index: int, calls: Sequence[BarrierCall]) -> list[BarrierBatch]:
    """Sync2 structs for lowered barrier calls (``rgraph.vk.lower``) on frame-in-flight set
    ``set_index``'s resources: one batch per vkCmdPipelineBarrier2, in order."""
    return [_dependency(resources, set_index, call) for call in calls]


def _family(index: int | None) -> int:
    return vk().VK_QUEUE_FAMILY_IGNORED if index is None else index


def _dependency(resources: ResourceSet, set_index: int, specs: Sequence[BarrierSpec]) -> BarrierBatch:
    v = vk()
    images, buffers, memory = [], [], []
    for b in specs:
        masks = {"srcStageMask": names.stages(b.src_stages), "srcAccessMask": names.accesses(b.src_access),
                 "dstStageMask": names.stages(b.dst_stages), "dstAccessMask": names.accesses(b.dst_access)}
        if b.resource is None:
            memory.append(v.VkMemoryBarrier2(**masks))
            continue
        r = resources.get(b.resource, set_index)
        masks |= {"srcQueueFamilyIndex": _family(b.src_family), "dstQueueFamilyIndex": _family(b.dst_family)}
        if r.is_image:
            sub = b.subresource
            rng = v.VkImageSubresourceRange(
                aspectMask=_aspect_for_layout(r.plan["format"], b.aspect_layout),
                baseMipLevel=sub["mips"][0], levelCount=sub["mips"][1] - sub["mips"][0],
                baseArrayLayer=sub["layers"][0], layerCount=sub["layers"][1] - sub["layers"][0])
            images.append(v.VkImageMemoryBarrier2(
                oldLayout=names.layout(b.old_layout), newLayout=names.layout(b.new_layout), image=r.handle,
                subresourceRange=rng, **masks))
        else:
            buffers.append(v.VkBufferMemoryBarrier2(buffer=r.handle, offset=0, size=names.WHOLE_SIZE, **masks))
    dep = v.VkDependencyInfo(
        memoryBarrierCount=len(memory), pMemoryBarriers=memory or None,
        imageMemoryBarrierCount=len(images), pImageMemoryBarriers=images or None,
        bufferMemoryBarrierCount=len(buffers), pBufferMemoryBarriers=buffers or None)
    return BarrierBatch(dep, [images, buffers, memory], len(images) + len(buffers) + len(memory))
