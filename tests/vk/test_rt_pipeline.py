"""Ray tracing pipelines and the recording context's trace calls on lavapipe: a raygen shader
sees the launch size of ``trace_rays`` and of ``trace_rays_indirect`` (arguments read from a
device address), and descriptor sets bound at the ray tracing bind point reach ray tracing
shaders (with the binding's wrong bind point value they read null descriptors on lavapipe:
``rgraph.vk.enum_fixes``). Which SBT group a ray selects is
data-checked by the probe (tests/vk/test_rt_runtime.py)."""

from __future__ import annotations

import struct

import pytest

pytestmark = pytest.mark.vulkan

HEADER = "#version 460\n#extension GL_EXT_ray_tracing : require\n"
RAYGEN = HEADER + """
layout(set = 0, binding = 0, std430) buffer Out { uint w[]; } o;
layout(push_constant) uniform P { uint base; } pc;
layout(location = 0) rayPayloadEXT uint payload;
void main() {
    uint i = gl_LaunchIDEXT.y * gl_LaunchSizeEXT.x + gl_LaunchIDEXT.x;
    if (i == 0u) { o.w[pc.base] = gl_LaunchSizeEXT.x; o.w[pc.base + 1u] = gl_LaunchSizeEXT.y; }
    atomicAdd(o.w[pc.base + 2u], 1u);
}
"""
MISS = HEADER + "layout(location = 0) rayPayloadInEXT uint payload;\nvoid main() { payload = 7u; }\n"
HIT = HEADER + "layout(location = 0) rayPayloadInEXT uint payload;\nvoid main() { payload = 9u; }\n"


@pytest.fixture
def rt_device():
    from rgraph.vk.device import create_device
    from rgraph.vk.errors import VulkanUnavailable
    from rgraph.vk.instance import create_instance

    try:
        instance = create_instance(False)
        device = create_device(instance, None, verbose=False, ray_tracing=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    yield device
    device.destroy()
    instance.destroy()


def test_trace_rays_and_trace_rays_indirect(rt_device):
    from rgraph.vk.accel import AddressBuffer
    from rgraph.vk.loader import vk
    from rgraph.vk.probe import compile_glsl
    from rgraph.vk.record import RecordContext
    from rgraph.vk.rt_pipeline import all_rt_stages, create_rt_pipeline

    v = vk()
    dev = rt_device.handle
    binding = [v.VkDescriptorSetLayoutBinding(binding=0, descriptorType=v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                              descriptorCount=1, stageFlags=all_rt_stages())]
    set_layout = v.vkCreateDescriptorSetLayout(dev, v.VkDescriptorSetLayoutCreateInfo(bindingCount=1,
                                                                                      pBindings=binding), None)
    pipe = create_rt_pipeline(rt_device, {"raygen": [compile_glsl(RAYGEN, "rgen")], "miss": [compile_glsl(MISS, "rmiss")],
                                          "closest_hit": [compile_glsl(HIT, "rchit")]}, [set_layout], push_bytes=4)
    out = AddressBuffer.create(rt_device, 64, v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT)
    out.host.write(b"\0" * 64)
    args = AddressBuffer.create(rt_device, 16, v.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT)
    args.host.write(struct.pack("<III", 3, 5, 1))
    sizes = [v.VkDescriptorPoolSize(type=v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, descriptorCount=1)]
    pool = v.vkCreateDescriptorPool(dev, v.VkDescriptorPoolCreateInfo(maxSets=1, poolSizeCount=1, pPoolSizes=sizes), None)
    ds = v.vkAllocateDescriptorSets(dev, v.VkDescriptorSetAllocateInfo(descriptorPool=pool, descriptorSetCount=1,
                                                                        pSetLayouts=[set_layout]))[0]
    info = v.VkDescriptorBufferInfo(buffer=out.host.handle, offset=0, range=64)
    v.vkUpdateDescriptorSets(dev, 1, [v.VkWriteDescriptorSet(dstSet=ds, dstBinding=0, descriptorCount=1,
                                                             descriptorType=v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                                             pBufferInfo=[info])], 0, None)
    cmd_pool = v.vkCreateCommandPool(dev, v.VkCommandPoolCreateInfo(queueFamilyIndex=rt_device.families["graphics"]),
                                     None)
    cb = v.vkAllocateCommandBuffers(dev, v.VkCommandBufferAllocateInfo(commandPool=cmd_pool, level=0,
                                                                       commandBufferCount=1))[0]
    v.vkBeginCommandBuffer(cb, v.VkCommandBufferBeginInfo())
    ctx = RecordContext(rt_device, cb)
    ctx.bind(pipe, [ds])
    ctx.push(pipe, struct.pack("<I", 0))
    ctx.trace_rays(pipe, 4, 2)
    ctx.push(pipe, struct.pack("<I", 4))
    ctx.trace_rays_indirect(pipe, args.address)
    v.vkEndCommandBuffer(cb)
    v.vkQueueSubmit(rt_device.queues["graphics"], 1, [v.VkSubmitInfo(commandBufferCount=1, pCommandBuffers=[cb])],
                    None)
    v.vkQueueWaitIdle(rt_device.queues["graphics"])
    words = struct.unpack("<16I", out.host.read(64))
    try:
        assert words[0:3] == (4, 2, 8)
        assert words[4:7] == (3, 5, 15)
    finally:
        v.vkDestroyCommandPool(dev, cmd_pool, None)
        v.vkDestroyDescriptorPool(dev, pool, None)
        pipe.destroy()
        v.vkDestroyDescriptorSetLayout(dev, set_layout, None)
        out.destroy()
        args.destroy()
