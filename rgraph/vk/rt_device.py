"""Ray tracing on the device: extensions, features and properties (VK_KHR_ray_tracing_pipeline,
VK_KHR_acceleration_structure, buffer device addresses), and ray queries (VK_KHR_ray_query)
where the device offers them: the probe of a compute or raster pass that reads an accel
(FORMAT.md 5) queries rays.

``create_device(..., ray_tracing=True)`` calls :func:`chain` to extend its feature chain and
extension list; extension commands come from :func:`proc` (vkGetDeviceProcAddr).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rgraph.vk.errors import VulkanUnavailable
from rgraph.vk.loader import vk

EXTENSIONS = ("VK_KHR_acceleration_structure", "VK_KHR_ray_tracing_pipeline", "VK_KHR_deferred_host_operations")
RAY_QUERY = "VK_KHR_ray_query"


@dataclass(frozen=True)
class RayTracingProperties:
    shader_group_handle_size: int
    shader_group_handle_alignment: int
    shader_group_base_alignment: int
    max_recursion_depth: int
    min_scratch_offset_alignment: int


def supported(physical: Any) -> bool:
    """Whether the physical device has the ray tracing pipeline extensions."""
    v = vk()
    names = {e.extensionName for e in v.vkEnumerateDeviceExtensionProperties(physical, None)}
    return all(e in names for e in EXTENSIONS)


def chain(physical: Any, device_name: str, next_struct: Any) -> tuple[Any, list[str]]:
    """Feature structs enabling acceleration structures and ray tracing pipelines, chained in
    front of ``next_struct``, and the extensions to enable. Raises when the device lacks them."""
    v = vk()
    if not supported(physical):
        raise VulkanUnavailable(f"{device_name} lacks ray tracing pipelines ({', '.join(EXTENSIONS)})")
    q_as = v.VkPhysicalDeviceAccelerationStructureFeaturesKHR()
    q_rt = v.VkPhysicalDeviceRayTracingPipelineFeaturesKHR(pNext=q_as)
    v.vkGetPhysicalDeviceFeatures2(physical, v.VkPhysicalDeviceFeatures2(pNext=q_rt))
    if not (q_as.accelerationStructure and q_rt.rayTracingPipeline):
        raise VulkanUnavailable(f"{device_name} lacks the accelerationStructure/rayTracingPipeline features")
    extensions = list(EXTENSIONS)
    head = next_struct
    names = {e.extensionName for e in v.vkEnumerateDeviceExtensionProperties(physical, None)}
    if RAY_QUERY in names:
        q_rq = v.VkPhysicalDeviceRayQueryFeaturesKHR()
        v.vkGetPhysicalDeviceFeatures2(physical, v.VkPhysicalDeviceFeatures2(pNext=q_rq))
        if q_rq.rayQuery:
            head = v.VkPhysicalDeviceRayQueryFeaturesKHR(pNext=head, rayQuery=v.VK_TRUE)
            extensions.append(RAY_QUERY)
    e_as = v.VkPhysicalDeviceAccelerationStructureFeaturesKHR(pNext=head, accelerationStructure=v.VK_TRUE)
    e_rt = v.VkPhysicalDeviceRayTracingPipelineFeaturesKHR(
        pNext=e_as, rayTracingPipeline=v.VK_TRUE,
        rayTracingPipelineTraceRaysIndirect=v.VK_TRUE if q_rt.rayTracingPipelineTraceRaysIndirect else v.VK_FALSE)
    return e_rt, extensions


def properties(physical: Any) -> RayTracingProperties:
    v = vk()
    rt = v.VkPhysicalDeviceRayTracingPipelinePropertiesKHR()
    acc = v.VkPhysicalDeviceAccelerationStructurePropertiesKHR(pNext=rt)
    v.vkGetPhysicalDeviceProperties2(physical, v.VkPhysicalDeviceProperties2(pNext=acc))
    return RayTracingProperties(
        int(rt.shaderGroupHandleSize), int(rt.shaderGroupHandleAlignment), int(rt.shaderGroupBaseAlignment),
        int(rt.maxRayRecursionDepth), int(acc.minAccelerationStructureScratchOffsetAlignment))


def proc(device: Any, name: str) -> Any:
    """A device-level extension command, cached on the ``rgraph.vk.device.Device``."""
    fns = device.__dict__.setdefault("_rt_fns", {})
    if name not in fns:
        fns[name] = vk().vkGetDeviceProcAddr(device.handle, name)
    return fns[name]


def device_address(device: Any, command: str, info: Any) -> int:
    """``vkGetBufferDeviceAddress`` / ``vkGetAccelerationStructureDeviceAddressKHR`` called
    directly: the binding's wrappers return their input struct instead of the address."""
    v = vk()
    fns = device.__dict__.setdefault("_rt_raw", {})
    if command not in fns:
        ptr = v.lib.vkGetDeviceProcAddr(device.handle, command.encode())
        if ptr == v.ffi.NULL:
            raise VulkanUnavailable(f"{command} is not available")
        fns[command] = v.ffi.cast(f"PFN_{command}", ptr)
    return int(fns[command](device.handle, v.ffi.addressof(info)))
