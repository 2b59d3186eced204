"""``RecordContext``: the commands a pass implementation may record (``PassImpl.record``):
draws, dispatches, copies, binds, push constants, ray traces and accel builds (``rgraph.vk.rt_record``). It has no barrier calls: the graph owns
synchronization (``rgraph.vk.lower``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.loader import vk
from rgraph.vk.rt_record import RayTracingCommands


class RecordContext(RayTracingCommands):
    """Commands a pass implementation may record. Deliberately no barriers (but ``make_available_to_host``)."""

    def __init__(self, device: Device, command_buffer: Any) -> None:
        self._device = device
        self._cb = command_buffer

    # pipeline state
    def bind_compute(self, pipeline: Any, layout: Any, descriptor_sets: list[Any]) -> None:
        v = vk()
        v.vkCmdBindPipeline(self._cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, pipeline)
        if descriptor_sets:
            v.vkCmdBindDescriptorSets(self._cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0,
                                      len(descriptor_sets), descriptor_sets, 0, None)

    def bind_graphics(self, pipeline: Any, layout: Any, descriptor_sets: list[Any]) -> None:
        v = vk()
        v.vkCmdBindPipeline(self._cb, v.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
        if descriptor_sets:
            v.vkCmdBindDescriptorSets(self._cb, v.VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0,
                                      len(descriptor_sets), descriptor_sets, 0, None)

    def bind(self, pipeline: Any, descriptor_sets: Sequence[Any] = (), first_set: int = 0) -> None:
        """Bind a ``rgraph.vk.passkit.Pipeline`` and descriptor sets from ``first_set``."""
        v = vk()
        v.vkCmdBindPipeline(self._cb, pipeline.bind_point, pipeline.pipeline)
        if descriptor_sets:
            v.vkCmdBindDescriptorSets(self._cb, pipeline.bind_point, pipeline.layout, first_set,
                                      len(descriptor_sets), list(descriptor_sets), 0, None)

    def push(self, pipeline: Any, data: bytes, offset: int = 0) -> None:
        """Push constants to a ``Pipeline`` (all of its push stages)."""
        self.push_constants(pipeline.layout, pipeline.push_stages, data, offset)

    def push_constants(self, layout: Any, stages: int, data: bytes, offset: int = 0) -> None:
        v = vk()
        buf = v.ffi.new("char[]", data)
        v.vkCmdPushConstants(self._cb, layout, stages, offset, len(data), buf)

    def bind_vertex_buffers(self, buffers: list[Any], offsets: list[int] | None = None) -> None:
        if buffers:
            vk().vkCmdBindVertexBuffers(self._cb, 0, len(buffers), buffers, offsets or [0] * len(buffers))

    def bind_index_buffer(self, buffer: Any, offset: int = 0) -> None:
        v = vk()
        v.vkCmdBindIndexBuffer(self._cb, buffer, offset, v.VK_INDEX_TYPE_UINT32)

    # render pass scope (attachments' layouts are the plan's; no implicit transitions)
    def begin_render_pass(self, render_pass: Any, framebuffer: Any, extent: tuple[int, int],
                          clear_values: list[Any]) -> None:
        v = vk()
        info = v.VkRenderPassBeginInfo(
            renderPass=render_pass, framebuffer=framebuffer,
            renderArea=v.VkRect2D(offset=v.VkOffset2D(x=0, y=0), extent=v.VkExtent2D(width=extent[0], height=extent[1])),
            clearValueCount=len(clear_values), pClearValues=clear_values or None)
        v.vkCmdBeginRenderPass(self._cb, info, v.VK_SUBPASS_CONTENTS_INLINE)

    def end_render_pass(self) -> None:
        vk().vkCmdEndRenderPass(self._cb)

    # work
    def draw(self, vertices: int, instances: int = 1, first_vertex: int = 0, first_instance: int = 0) -> None:
        vk().vkCmdDraw(self._cb, vertices, instances, first_vertex, first_instance)

    def draw_indexed(self, indices: int, instances: int = 1, first_index: int = 0, vertex_offset: int = 0,
                     first_instance: int = 0) -> None:
        vk().vkCmdDrawIndexed(self._cb, indices, instances, first_index, vertex_offset, first_instance)

    def draw_indexed_each(self, indices: int, first_index: int, vertex_offset: int, instances: list[int]) -> None:
        """One ``vkCmdDrawIndexed`` per id in ``instances`` (firstInstance = the id, one
        instance each): the raw cffi call in a loop, as an engine's per-object draws."""
        draw, cb = vk().lib.vkCmdDrawIndexed, self._cb
        for d in instances:
            draw(cb, indices, 1, first_index, vertex_offset, d)

    def draw_indirect(self, buffer: Any, offset: int) -> None:
        vk().vkCmdDrawIndirect(self._cb, buffer, offset, 1, 16)

    def draw_indexed_indirect(self, buffer: Any, offset: int) -> None:
        vk().vkCmdDrawIndexedIndirect(self._cb, buffer, offset, 1, 20)

    def draw_indexed_indirect_count(self, buffer: Any, offset: int, count_buffer: Any, count_offset: int,
                                    max_draws: int) -> None:
        """Vulkan 1.2 ``vkCmdDrawIndexedIndirectCount`` (stride 20: VkDrawIndexedIndirectCommand)."""
        vk().vkCmdDrawIndexedIndirectCount(self._cb, buffer, offset, count_buffer, count_offset, max_draws, 20)

    def dispatch(self, x: int, y: int, z: int = 1) -> None:
        vk().vkCmdDispatch(self._cb, x, y, z)

    def dispatch_indirect(self, buffer: Any, offset: int) -> None:
        vk().vkCmdDispatchIndirect(self._cb, buffer, offset)

    def copy_buffer(self, src: Any, dst: Any, regions: list[Any]) -> None:
        vk().vkCmdCopyBuffer(self._cb, src, dst, len(regions), regions)

    def copy_image(self, src: Any, src_layout: int, dst: Any, dst_layout: int, regions: list[Any]) -> None:
        vk().vkCmdCopyImage(self._cb, src, src_layout, dst, dst_layout, len(regions), regions)

    def copy_buffer_to_image(self, src: Any, dst: Any, dst_layout: int, regions: list[Any]) -> None:
        vk().vkCmdCopyBufferToImage(self._cb, src, dst, dst_layout, len(regions), regions)

    def copy_image_to_buffer(self, src: Any, src_layout: int, dst: Any, regions: list[Any]) -> None:
        vk().vkCmdCopyImageToBuffer(self._cb, src, src_layout, dst, len(regions), regions)

    def make_available_to_host(self, buffer: Any) -> None:
        """The one barrier a pass may record: its copy's writes to ``buffer`` made available to
        the host (COPY -> HOST), for a buffer another device reads through host memory after
        the host waited for this frame (rgraph.vk.multi.host_memory). The plan's barriers are
        device-side only; this one orders nothing on the device."""
        v = vk()
        b = v.VkBufferMemoryBarrier2(srcStageMask=v.VK_PIPELINE_STAGE_2_COPY_BIT,
                                     srcAccessMask=v.VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                     dstStageMask=v.VK_PIPELINE_STAGE_2_HOST_BIT, dstAccessMask=v.VK_ACCESS_2_HOST_READ_BIT,
                                     srcQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED,
                                     dstQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED, buffer=buffer, offset=0,
                                     size=names.WHOLE_SIZE)
        v.vkCmdPipelineBarrier2(self._cb, v.VkDependencyInfo(bufferMemoryBarrierCount=1, pBufferMemoryBarriers=[b]))
