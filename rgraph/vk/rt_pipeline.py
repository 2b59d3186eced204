"""Ray tracing pipelines and their shader binding tables (VK_KHR_ray_tracing_pipeline).

Groups in order: the raygen shader, one general group per miss shader, one triangles hit group
per closest-hit shader (with the any-hit shader of the same index, when given). The SBT is one
host-visible buffer with a device address: raygen, miss and hit regions, each aligned to
``shaderGroupBaseAlignment``, records of the handle size aligned to ``shaderGroupHandleAlignment``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rgraph.vk.accel import AddressBuffer
from rgraph.vk.device import Device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.rt_device import proc, properties

RT_STAGES = ("raygen", "miss", "closest_hit", "any_hit")
SBT_USAGE = 0x400  # VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR


def _align(value: int, alignment: int) -> int:
    return -(-value // alignment) * alignment


@dataclass
class RayTracingPipeline:
    """What ``RecordContext.bind``/``trace_rays`` need (same fields as ``passkit.Pipeline``)."""

    device: Device
    pipeline: Any
    layout: Any
    push_stages: int
    sbt: AddressBuffer
    regions: tuple[Any, Any, Any, Any]  # raygen, miss, hit, callable VkStridedDeviceAddressRegionKHR
    owned_layout: bool = True
    modules: list[Any] = field(default_factory=list)

    @property
    def bind_point(self) -> int:
        return vk().VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR

    def destroy(self) -> None:
        v = vk()
        v.vkDestroyPipeline(self.device.handle, self.pipeline, None)
        if self.owned_layout:
            v.vkDestroyPipelineLayout(self.device.handle, self.layout, None)
        for m in self.modules:
            v.vkDestroyShaderModule(self.device.handle, m, None)
        self.sbt.destroy()


def stage_bits() -> dict[str, int]:
    v = vk()
    return {"raygen": v.VK_SHADER_STAGE_RAYGEN_BIT_KHR, "miss": v.VK_SHADER_STAGE_MISS_BIT_KHR,
            "closest_hit": v.VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR, "any_hit": v.VK_SHADER_STAGE_ANY_HIT_BIT_KHR}


def all_rt_stages() -> int:
    out = 0
    for bit in stage_bits().values():
        out |= bit
    return out


def create_rt_pipeline(device: Device, shaders: dict[str, list[bytes]], set_layouts: list[Any],
                       push_bytes: int = 0, max_depth: int = 1, layout: Any = None) -> RayTracingPipeline:
    """A pipeline from SPIR-V per stage (``raygen``: exactly one; ``miss``/``closest_hit``:
    at least one; ``any_hit``: optional, paired with closest-hit shaders by index)."""
    v = vk()
    props = properties(device.physical.handle)
    if len(shaders.get("raygen", [])) != 1 or not shaders.get("miss") or not shaders.get("closest_hit"):
        raise ExecutionError("a ray tracing pipeline needs one raygen, and miss and closest-hit shaders")
    if max_depth > props.max_recursion_depth:
        raise ExecutionError(f"ray recursion depth {max_depth} exceeds the device's {props.max_recursion_depth}")
    bits = stage_bits()
    entry = v.ffi.new("char[]", b"main")  # kept alive over the call (nested strings die early in the binding)
    modules, stages, index = [], [], {}
    for kind in RT_STAGES:
        for n, spirv in enumerate(shaders.get(kind, [])):
            module = v.vkCreateShaderModule(device.handle, v.VkShaderModuleCreateInfo(codeSize=len(spirv),
                                                                                     pCode=spirv), None)
            modules.append(module)
            index[(kind, n)] = len(stages)
            stages.append({"sType": v.VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, "stage": bits[kind],
                           "module": module, "pName": entry})
    unused = v.VK_SHADER_UNUSED_KHR
    general = v.VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR
    groups = [_group(v, type=general, generalShader=index[("raygen", 0)],
                                                     closestHitShader=unused, anyHitShader=unused,
                                                     intersectionShader=unused)]
    for n in range(len(shaders["miss"])):
        groups.append(_group(v, type=general, generalShader=index[("miss", n)],
                                                             closestHitShader=unused, anyHitShader=unused,
                                                             intersectionShader=unused))
    for n in range(len(shaders["closest_hit"])):
        groups.append(_group(
            v, type=v.VK_RAY_TRACING_SHADER_GROUP_TYPE_TRIANGLES_HIT_GROUP_KHR, generalShader=unused,
            closestHitShader=index[("closest_hit", n)], anyHitShader=index.get(("any_hit", n), unused),
            intersectionShader=unused))
    owned = layout is None
    if owned:
        ranges = ([v.VkPushConstantRange(stageFlags=all_rt_stages(), offset=0, size=push_bytes)] if push_bytes else [])
        layout = v.vkCreatePipelineLayout(device.handle, v.VkPipelineLayoutCreateInfo(
            setLayoutCount=len(set_layouts), pSetLayouts=set_layouts or None, pushConstantRangeCount=len(ranges),
            pPushConstantRanges=ranges or None), None)
    # arrays made here and kept alive over the call (the binding frees inline-built ones early)
    stage_array = v.ffi.new("VkPipelineShaderStageCreateInfo[]", stages)
    group_array = v.ffi.new("VkRayTracingShaderGroupCreateInfoKHR[]", groups)
    dynamic = v.ffi.new("VkPipelineDynamicStateCreateInfo*", {
        "sType": v.VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO, "dynamicStateCount": 0})
    info = v.ffi.new("VkRayTracingPipelineCreateInfoKHR*", {
        "sType": v.VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR, "stageCount": len(stages),
        "pStages": stage_array, "groupCount": len(groups), "pGroups": group_array,
        "maxPipelineRayRecursionDepth": max_depth, "layout": layout, "pDynamicState": dynamic})
    create = proc(device, "vkCreateRayTracingPipelinesKHR")
    out = v.ffi.new("VkPipeline[1]")
    create(device.handle, None, None, 1, info, None, out)
    pipeline = out[0]
    sbt, regions = _binding_table(device, pipeline, len(shaders["miss"]), len(shaders["closest_hit"]), props)
    return RayTracingPipeline(device, pipeline, layout, all_rt_stages() if push_bytes else 0, sbt, regions, owned,
                              modules)


def _group(v, **fields) -> dict:
    """A VkRayTracingShaderGroupCreateInfoKHR initializer (every field explicit)."""
    return {"sType": v.VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR, "pNext": v.ffi.NULL,
            "pShaderGroupCaptureReplayHandle": v.ffi.NULL, **fields}


def _binding_table(device: Device, pipeline: Any, misses: int, hits: int, props) -> tuple[AddressBuffer, tuple]:
    v = vk()
    size = props.shader_group_handle_size
    stride = _align(size, props.shader_group_handle_alignment)
    base = props.shader_group_base_alignment
    groups = 1 + misses + hits
    handles = v.ffi.new("char[]", size * groups)
    get = proc(device, "vkGetRayTracingShaderGroupHandlesKHR")
    get(device.handle, pipeline, 0, groups, size * groups, handles)
    raw = v.ffi.buffer(handles, size * groups)[:]
    raygen_size = _align(stride, base)
    miss_offset = raygen_size
    miss_size = _align(stride * misses, base)
    hit_offset = miss_offset + miss_size
    hit_size = _align(stride * hits, base)
    sbt = AddressBuffer.create(device, hit_offset + hit_size + base, SBT_USAGE)
    start = _align(sbt.address, base) - sbt.address  # region addresses must be base-aligned
    data = bytearray(start + hit_offset + hit_size)

    def put(offset: int, group: int) -> None:
        data[start + offset:start + offset + size] = raw[group * size:(group + 1) * size]

    put(0, 0)
    for n in range(misses):
        put(miss_offset + n * stride, 1 + n)
    for n in range(hits):
        put(hit_offset + n * stride, 1 + misses + n)
    sbt.host.write(bytes(data))
    addr = sbt.address + start
    region = v.VkStridedDeviceAddressRegionKHR
    regions = (region(deviceAddress=addr, stride=raygen_size, size=raygen_size),
               region(deviceAddress=addr + miss_offset, stride=stride, size=miss_size),
               region(deviceAddress=addr + hit_offset, stride=stride, size=hit_size),
               region(deviceAddress=0, stride=0, size=0))
    return sbt, regions
