"""Debug names for Vulkan objects (``vkSetDebugUtilsObjectNameEXT``), so that validation
messages and GPU debuggers name ``depth`` rather than ``VkImage 0x2...``. A device without
VK_EXT_debug_utils skips naming."""

from __future__ import annotations

from typing import Any

from rgraph.vk.loader import vk


def name_object(device: Any, handle: Any, object_type: int, name: str) -> None:
    """Give ``handle`` (of ``object_type``, a ``VK_OBJECT_TYPE_*``) the debug name ``name``."""
    fn = device.fn("vkSetDebugUtilsObjectNameEXT")
    if not fn:
        return
    v = vk()
    raw = int(v.ffi.cast("uint64_t", handle))
    fn(device.handle, v.VkDebugUtilsObjectNameInfoEXT(objectType=object_type, objectHandle=raw, pObjectName=name))


def resource_name(res: dict, set_index: int, copies: int) -> str:
    """``depth``, or ``depth (frame set 1)`` when every frame in flight has its own copy."""
    return res["name"] if copies == 1 else f"{res['name']} (frame set {set_index})"
