"""Device-local buffers filled once at load through a host staging buffer (pass-owned tables:
scene geometry read by compute and ray tracing shaders every frame should not cross the bus)."""

from __future__ import annotations

from typing import Any

from rgraph.vk.loader import vk
from rgraph.vk.resources import HostBuffer, memory_type


def upload_static(device: Any, payload: bytes, usage: int) -> tuple[Any, Any, int]:
    """(buffer, memory, size) of a new DEVICE_LOCAL buffer holding ``payload``: copied from a
    staging buffer on the graphics queue, waited for, then a barrier from the copy to every
    later read (the frames' submits come later on the same queue)."""
    v = vk()
    dev = device.handle
    size = max(len(payload), 16)
    handle = v.vkCreateBuffer(dev, v.VkBufferCreateInfo(size=size, usage=usage | v.VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                        sharingMode=v.VK_SHARING_MODE_EXCLUSIVE), None)
    req = v.vkGetBufferMemoryRequirements(dev, handle)
    memory = v.vkAllocateMemory(dev, v.VkMemoryAllocateInfo(
        allocationSize=req.size, memoryTypeIndex=memory_type(device, req.memoryTypeBits,
                                                             v.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)), None)
    v.vkBindBufferMemory(dev, handle, memory, 0)
    staging = HostBuffer.create(device, size, v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
    pool = v.vkCreateCommandPool(dev, v.VkCommandPoolCreateInfo(queueFamilyIndex=device.families["graphics"]), None)
    fence = v.vkCreateFence(dev, v.VkFenceCreateInfo(), None)
    try:
        staging.write(payload.ljust(size, b"\0"))
        cb = v.vkAllocateCommandBuffers(dev, v.VkCommandBufferAllocateInfo(
            commandPool=pool, level=v.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1))[0]
        v.vkBeginCommandBuffer(cb, v.VkCommandBufferBeginInfo(flags=v.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))
        v.vkCmdCopyBuffer(cb, staging.handle, handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0, size=size)])
        barrier = v.VkBufferMemoryBarrier2(
            srcStageMask=v.VK_PIPELINE_STAGE_2_COPY_BIT, srcAccessMask=v.VK_ACCESS_2_TRANSFER_WRITE_BIT,
            dstStageMask=v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, dstAccessMask=v.VK_ACCESS_2_MEMORY_READ_BIT,
            srcQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED, dstQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED,
            buffer=handle, offset=0, size=size)
        v.vkCmdPipelineBarrier2(cb, v.VkDependencyInfo(bufferMemoryBarrierCount=1, pBufferMemoryBarriers=[barrier]))
        v.vkEndCommandBuffer(cb)
        submit = v.VkSubmitInfo2(commandBufferInfoCount=1, pCommandBufferInfos=[v.VkCommandBufferSubmitInfo(commandBuffer=cb)])
        v.vkQueueSubmit2(device.queues["graphics"], 1, [submit], fence)
        v.vkWaitForFences(dev, 1, [fence], v.VK_TRUE, device.fence_timeout_ns)
    finally:
        v.vkDestroyFence(dev, fence, None)
        v.vkDestroyCommandPool(dev, pool, None)
        staging.destroy()
    return handle, memory, size
