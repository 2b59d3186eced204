"""Memory requirements measured on the live device (vkGetDevice*MemoryRequirements, maintenance4)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.loader import vk

Requirements = tuple[int, int, int]  # (size, alignment, memory_type_bits)


def image_create_info(format_name: str, extent: Sequence[int], mips: int, layers: int, samples: int,
                      usage_names: Sequence[str], alias: bool = False):
    """The VkImageCreateInfo the runtime uses for a plan image (2D or 3D by extent depth)."""
    v = vk()
    depth = int(extent[2]) if len(extent) > 2 else 1
    return v.VkImageCreateInfo(
        flags=v.VK_IMAGE_CREATE_ALIAS_BIT_KHR if alias else 0,
        imageType=v.VK_IMAGE_TYPE_3D if depth > 1 else v.VK_IMAGE_TYPE_2D,
        format=names.format_value(format_name),
        extent=v.VkExtent3D(width=int(extent[0]), height=int(extent[1]), depth=depth),
        mipLevels=int(mips), arrayLayers=int(layers), samples=names.sample_count(samples),
        tiling=v.VK_IMAGE_TILING_OPTIMAL, usage=names.image_usage(usage_names),
        sharingMode=v.VK_SHARING_MODE_EXCLUSIVE, initialLayout=v.VK_IMAGE_LAYOUT_UNDEFINED,
    )


def buffer_create_info(size: int, usage_names: Sequence[str]):
    v = vk()
    return v.VkBufferCreateInfo(size=int(size), usage=names.buffer_usage(usage_names),
                                sharingMode=v.VK_SHARING_MODE_EXCLUSIVE)


class DeviceMemoryRequirements:
    """The memory-requirements provider backed by a live device (same API as the profile one)."""

    def __init__(self, device: Device) -> None:
        self.device = device
        self.name = device.name

    def image(self, format_vk_name: str, extent: Sequence[int], mips: int, layers: int, samples: int,
              usage_names: Sequence[str]) -> Requirements:
        v = vk()
        info = image_create_info(format_vk_name, extent, mips, layers, samples, usage_names)
        query = v.VkDeviceImageMemoryRequirements(pCreateInfo=info, planeAspect=0)
        # Pass our own output struct: the binding's default is zero-filled (sType 0), which
        # lavapipe ignores but NVIDIA's driver leaves unwritten (size and alignment 0).
        out = v.VkMemoryRequirements2()
        v.vkGetDeviceImageMemoryRequirements(self.device.handle, query, out)
        req = out.memoryRequirements
        return int(req.size), int(req.alignment), int(req.memoryTypeBits)

    def accel_sizes(self, level: str, count: int, max_vertex: int, update: bool) -> tuple[int, int, int]:
        from rgraph.vk import accel_sizes

        self._require_rt()
        return accel_sizes.query(self.device, level, count, max_vertex, update=update)

    def accel_scratch_alignment(self) -> int:
        from rgraph.vk.rt_device import properties

        self._require_rt()
        return properties(self.device.physical.handle).min_scratch_offset_alignment

    def _require_rt(self) -> None:
        if "accelerationStructure" not in self.device.enabled_features:
            from rgraph.errors import RGraphError

            raise RGraphError.in_file("<device>", f"{self.device.name} was opened without acceleration structures")

    def buffer(self, size: int, usage_names: Sequence[str]) -> Requirements:
        v = vk()
        info = buffer_create_info(size, usage_names)
        query = v.VkDeviceBufferMemoryRequirements(pCreateInfo=info)
        out = v.VkMemoryRequirements2()
        v.vkGetDeviceBufferMemoryRequirements(self.device.handle, query, out)
        req = out.memoryRequirements
        return int(req.size), int(req.alignment), int(req.memoryTypeBits)


@contextmanager
def live_requirements(device_index: int | None = None) -> Iterator[tuple[DeviceMemoryRequirements, Device]]:
    """The memory-requirements provider of the live device that ``execute_plan(...,
    device_index=device_index)`` will use, and that device; both destroyed on exit."""
    from rgraph.vk.device import choose_physical_device, create_device, list_physical_devices
    from rgraph.vk.instance import create_instance
    from rgraph.vk.rt_device import supported

    instance = create_instance(validate=False)
    try:
        physical = choose_physical_device(list_physical_devices(instance), device_index)
        device = create_device(instance, device_index, verbose=False, ray_tracing=supported(physical.handle))
        try:
            yield DeviceMemoryRequirements(device), device
        finally:
            device.destroy()
    finally:
        instance.destroy()


def compile_for_device(graph: Any, device_index: int | None = None, **options: Any) -> dict:
    """``compile_graph(graph, **options)`` with sizes and alignments from the live device that
    ``execute_plan(..., device_index=device_index)`` will use (a plan compiled for another
    device's profile is refused by the runtime's requirements cross-check)."""
    from rgraph.compiler.pipeline import compile_graph

    with live_requirements(device_index) as (memory, _device):
        return compile_graph(graph, memory=memory, **options)
