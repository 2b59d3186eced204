"""Device-local buffers outside the plan (the scene's geometry and tables): create, fill once
through a staging buffer, read back (tests), destroy.

``submit_once(queue, record)`` records ``record(cb)`` into a one-time command buffer on plan
queue ``queue``, submits it and waits (the executor's, or ``one_time_submitter``'s).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.loader import vk
from rgraph.vk.resources import HostBuffer, memory_type

SubmitOnce = Callable[[str, Callable[[Any], None]], None]


@dataclass
class DeviceBuffer:
    handle: Any
    memory: Any
    size: int


class DeviceLocal:
    """Owns device-local buffers (each with its own memory) until ``destroy``."""

    def __init__(self, device: Device) -> None:
        self.device = device
        self.buffers: list[DeviceBuffer] = []

    def buffer(self, size: int, usage: int) -> DeviceBuffer:
        """A buffer of at least 16 bytes; ``usage`` plus transfer source and destination."""
        v = vk()
        dev = self.device.handle
        size = max(int(size), 16)
        usage |= v.VK_BUFFER_USAGE_TRANSFER_DST_BIT | v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT
        handle = v.vkCreateBuffer(dev, v.VkBufferCreateInfo(size=size, usage=usage,
                                                            sharingMode=v.VK_SHARING_MODE_EXCLUSIVE), None)
        req = v.vkGetBufferMemoryRequirements(dev, handle)
        index = memory_type(self.device, req.memoryTypeBits, v.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)
        memory = v.vkAllocateMemory(dev, v.VkMemoryAllocateInfo(allocationSize=req.size, memoryTypeIndex=index), None)
        v.vkBindBufferMemory(dev, handle, memory, 0)
        buf = DeviceBuffer(handle, memory, size)
        self.buffers.append(buf)
        return buf

    def upload(self, submit_once: SubmitOnce, uploads: list[tuple[DeviceBuffer, bytes]]) -> None:
        """Copy each payload to its buffer's start, then a barrier COPY -> ALL_COMMANDS/MEMORY_READ
        in the same command buffer (a fence wait alone does not make device writes visible)."""
        v = vk()
        uploads = [(b, d) for b, d in uploads if d]
        if not uploads:
            return
        offsets, total = [], 0
        for _buf, payload in uploads:
            offsets.append(total)
            total += (len(payload) + 15) // 16 * 16
        staging = HostBuffer.create(self.device, max(total, 16), v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
        try:
            for (_buf, payload), off in zip(uploads, offsets, strict=True):
                staging.write(payload, off)

            def record(cb: Any) -> None:
                for (buf, payload), off in zip(uploads, offsets, strict=True):
                    v.vkCmdCopyBuffer(cb, staging.handle, buf.handle, 1,
                                      [v.VkBufferCopy(srcOffset=off, dstOffset=0, size=len(payload))])
                barrier(cb, [buf.handle for buf, _payload in uploads], v.VK_PIPELINE_STAGE_2_COPY_BIT,
                        v.VK_ACCESS_2_TRANSFER_WRITE_BIT, v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                        v.VK_ACCESS_2_MEMORY_READ_BIT)

            submit_once("graphics", record)
        finally:
            staging.destroy()

    def read(self, submit_once: SubmitOnce, buf: DeviceBuffer, src_stage: int, src_access: int) -> bytes:
        """The buffer's bytes, after the writes of (``src_stage``, ``src_access``) submitted earlier."""
        v = vk()
        staging = HostBuffer.create(self.device, buf.size, v.VK_BUFFER_USAGE_TRANSFER_DST_BIT, readback=True)
        try:
            def record(cb: Any) -> None:
                barrier(cb, [buf.handle], src_stage, src_access, v.VK_PIPELINE_STAGE_2_COPY_BIT,
                        v.VK_ACCESS_2_TRANSFER_READ_BIT)
                v.vkCmdCopyBuffer(cb, buf.handle, staging.handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0,
                                                                                      size=buf.size)])
                barrier(cb, [staging.handle], v.VK_PIPELINE_STAGE_2_COPY_BIT, v.VK_ACCESS_2_TRANSFER_WRITE_BIT,
                        v.VK_PIPELINE_STAGE_2_HOST_BIT, v.VK_ACCESS_2_HOST_READ_BIT)

            submit_once("graphics", record)
            return staging.read(buf.size)
        finally:
            staging.destroy()

    def destroy(self) -> None:
        v = vk()
        for buf in reversed(self.buffers):
            v.vkDestroyBuffer(self.device.handle, buf.handle, None)
            v.vkFreeMemory(self.device.handle, buf.memory, None)
        self.buffers = []


def barrier(cb: Any, buffers: list[Any], src_stage: int, src_access: int, dst_stage: int, dst_access: int) -> None:
    """One vkCmdPipelineBarrier2 with a whole-buffer barrier per buffer (no queue transfer)."""
    v = vk()
    barriers = [v.VkBufferMemoryBarrier2(
        srcStageMask=src_stage, srcAccessMask=src_access, dstStageMask=dst_stage, dstAccessMask=dst_access,
        srcQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED, dstQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED,
        buffer=b, offset=0, size=names.WHOLE_SIZE) for b in buffers]
    v.vkCmdPipelineBarrier2(cb, v.VkDependencyInfo(bufferMemoryBarrierCount=len(barriers),
                                                   pBufferMemoryBarriers=barriers))


def submit_and_wait(device: Device, cmd_pool: Any, queue: str, record: Callable[[Any], None]) -> None:
    """Record (``record(cb)``) a one-time command buffer from ``cmd_pool``, submit it on plan
    queue ``queue``, wait for it and free it."""
    v = vk()
    cb = v.vkAllocateCommandBuffers(device.handle, v.VkCommandBufferAllocateInfo(
        commandPool=cmd_pool, level=v.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1))[0]
    v.vkBeginCommandBuffer(cb, v.VkCommandBufferBeginInfo(flags=v.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))
    record(cb)
    v.vkEndCommandBuffer(cb)
    fence = v.vkCreateFence(device.handle, v.VkFenceCreateInfo(), None)
    cb_info = v.VkCommandBufferSubmitInfo(commandBuffer=cb)
    submit = v.VkSubmitInfo2(commandBufferInfoCount=1, pCommandBufferInfos=[cb_info])
    v.vkQueueSubmit2(device.queues[queue], 1, [submit], fence)
    v.vkWaitForFences(device.handle, 1, [fence], v.VK_TRUE, device.fence_timeout_ns)
    v.vkDestroyFence(device.handle, fence, None)
    v.vkFreeCommandBuffers(device.handle, cmd_pool, 1, [cb])


@contextmanager
def one_time_submitter(device: Device) -> Iterator[SubmitOnce]:
    """A ``submit_once`` of its own (one command pool per queue family, destroyed at exit)."""
    v = vk()
    pools: dict[int, Any] = {}

    def submit_once(queue: str, record: Callable[[Any], None]) -> None:
        family = device.families[queue]
        if family not in pools:
            pools[family] = v.vkCreateCommandPool(device.handle, v.VkCommandPoolCreateInfo(queueFamilyIndex=family), None)
        submit_and_wait(device, pools[family], queue, record)

    try:
        yield submit_once
    finally:
        for p in pools.values():
            v.vkDestroyCommandPool(device.handle, p, None)
