"""One host allocation imported into several devices (``VK_EXT_external_memory_host``).

The sending device copies its band straight into host memory, the receiving device copies
it straight out: no readback buffer, no host copy, no staging upload (the study's redundant
host -> host memmove is gone). Each device gets its own ``VkBuffer`` (created with
``VkExternalMemoryBufferCreateInfo``) bound to ``VkDeviceMemory`` imported from the same
pointer (``VkImportMemoryHostPointerInfoEXT``); the pointer and size are multiples of every
device's ``minImportedHostPointerAlignment``.

Ordering is the host's: the sender's frame is fenced before the receiver's frame that reads
the bytes is submitted, and the sender's download makes its writes available to the host
(``RecordContext.make_available_to_host``), so the receiver's submit sees them as host writes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.loader import vk
from rgraph.vk.resources import memory_type

HOST_IMPORT = "VK_EXT_external_memory_host"


def supported(device: Device) -> bool:
    """Whether ``device`` was created with VK_EXT_external_memory_host (``rgraph.vk.device``
    enables it wherever it is offered)."""
    return HOST_IMPORT in getattr(device, "extensions", ())


def import_alignment(device: Device) -> int:
    v = vk()
    host = v.VkPhysicalDeviceExternalMemoryHostPropertiesEXT()
    props = v.VkPhysicalDeviceProperties2(pNext=host)
    v.vkGetPhysicalDeviceProperties2(device.physical.handle, props)
    return int(host.minImportedHostPointerAlignment)


def _round_up(n: int, a: int) -> int:
    return (n + a - 1) // a * a


@dataclass
class SharedHostBuffer:
    """``size`` bytes of host memory with one imported ``VkBuffer`` per (device, usages)."""

    size: int
    owner: Any  # the cffi allocation the pointer lies in (freed with this object)
    pointer: Any  # void*, aligned
    buffers: list[Any] = field(default_factory=list)
    _imports: list[tuple[Device, Any, Any]] = field(default_factory=list)  # (device, buffer, memory)

    @classmethod
    def create(cls, size: int, users: list[tuple[Device, list[str]]]) -> SharedHostBuffer:
        """One buffer per ``(device, usage names)`` in ``users``, all on the same bytes."""
        v = vk()
        handle_type = v.VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT
        created = []
        for device, usages in users:
            ext = v.VkExternalMemoryBufferCreateInfo(handleTypes=handle_type)
            info = v.VkBufferCreateInfo(pNext=ext, size=int(size), usage=names.buffer_usage(usages),
                                        sharingMode=v.VK_SHARING_MODE_EXCLUSIVE)
            buf = v.vkCreateBuffer(device.handle, info, None)
            created.append((device, buf, v.vkGetBufferMemoryRequirements(device.handle, buf)))
        align = max(import_alignment(d) for d, _u in users)
        total = _round_up(max([int(size)] + [int(req.size) for _d, _b, req in created]), align)
        owner = v.ffi.new("char[]", total + align)
        address = _round_up(int(v.ffi.cast("uintptr_t", owner)), align)
        out = cls(total, owner, v.ffi.cast("void*", address))
        try:
            for device, buf, req in created:
                get = v.vkGetDeviceProcAddr(device.handle, "vkGetMemoryHostPointerPropertiesEXT")
                props = v.VkMemoryHostPointerPropertiesEXT()  # the wrapper's own would lack sType
                get(device.handle, handle_type, out.pointer, props)
                bits = int(props.memoryTypeBits) & int(req.memoryTypeBits)
                index = memory_type(device, bits, 0, avoid=0)
                imported = v.VkImportMemoryHostPointerInfoEXT(handleType=handle_type, pHostPointer=out.pointer)
                memory = v.vkAllocateMemory(device.handle, v.VkMemoryAllocateInfo(
                    pNext=imported, allocationSize=total, memoryTypeIndex=index), None)
                v.vkBindBufferMemory(device.handle, buf, memory, 0)
                out._imports.append((device, buf, memory))
                out.buffers.append(buf)
        except BaseException:
            for device, buf, _req in created[len(out._imports):]:
                v.vkDestroyBuffer(device.handle, buf, None)
            out.destroy()
            raise
        return out

    def read(self, size: int | None = None) -> bytes:
        """The bytes as the host sees them (tests)."""
        v = vk()
        return bytes(v.ffi.buffer(v.ffi.cast("char*", self.pointer), self.size if size is None else size))

    def destroy(self) -> None:
        v = vk()
        for device, buf, memory in reversed(self._imports):
            v.vkDestroyBuffer(device.handle, buf, None)
            v.vkFreeMemory(device.handle, memory, None)
        self._imports = []
        self.buffers = []
        self.owner = None
