"""vkGetAccelerationStructureBuildSizesKHR over triangle BLAS and instance TLAS descriptions.

The geometry structs the size query and the builds (``rgraph.vk.accel``) share are made here, so
the plan's sizes are those of the builds the runtime records.
"""

from __future__ import annotations

from typing import Any

from rgraph.vk.loader import vk
from rgraph.vk.rt_device import proc

VERTEX_STRIDE = 12  # float32 x, y, z


def triangles_geometry(vertex_address: int, index_address: int, max_vertex: int, opaque: bool = True) -> Any:
    v = vk()
    tri = v.VkAccelerationStructureGeometryTrianglesDataKHR(
        vertexFormat=v.VK_FORMAT_R32G32B32_SFLOAT,
        vertexData=v.VkDeviceOrHostAddressConstKHR(deviceAddress=vertex_address), vertexStride=VERTEX_STRIDE,
        maxVertex=max(int(max_vertex), 0), indexType=v.VK_INDEX_TYPE_UINT32,
        indexData=v.VkDeviceOrHostAddressConstKHR(deviceAddress=index_address))
    return v.VkAccelerationStructureGeometryKHR(
        geometryType=v.VK_GEOMETRY_TYPE_TRIANGLES_KHR,
        geometry=v.VkAccelerationStructureGeometryDataKHR(triangles=tri),
        flags=v.VK_GEOMETRY_OPAQUE_BIT_KHR if opaque else 0)


def instances_geometry(instance_address: int) -> Any:
    v = vk()
    inst = v.VkAccelerationStructureGeometryInstancesDataKHR(
        arrayOfPointers=v.VK_FALSE, data=v.VkDeviceOrHostAddressConstKHR(deviceAddress=instance_address))
    return v.VkAccelerationStructureGeometryKHR(
        geometryType=v.VK_GEOMETRY_TYPE_INSTANCES_KHR, geometry=v.VkAccelerationStructureGeometryDataKHR(instances=inst),
        flags=v.VK_GEOMETRY_OPAQUE_BIT_KHR)


def build_flags(update: bool, compact: bool) -> int:
    v = vk()
    flags = v.VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR
    if update:
        flags |= v.VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR
    if compact:
        flags |= v.VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR
    return flags


def query(device: Any, level: str, count: int, max_vertex: int = 0, update: bool = False, *,
          compact: bool = False) -> tuple[int, int, int]:
    """(accelerationStructureSize, buildScratchSize, updateScratchSize) of one BLAS of ``count``
    triangles over ``max_vertex + 1`` vertices, or of a TLAS of ``count`` instances."""
    v = vk()
    geometry = (triangles_geometry(0, 0, max_vertex) if level == "bottom" else instances_geometry(0))
    info = v.VkAccelerationStructureBuildGeometryInfoKHR(
        type=(v.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR if level == "bottom"
              else v.VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR),
        flags=build_flags(update, compact), mode=v.VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR,
        geometryCount=1, pGeometries=[geometry])
    out = v.VkAccelerationStructureBuildSizesInfoKHR()
    fn = proc(device, "vkGetAccelerationStructureBuildSizesKHR")
    fn(device.handle, v.VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, info, [int(count)], out)
    return int(out.accelerationStructureSize), int(out.buildScratchSize), int(out.updateScratchSize)
