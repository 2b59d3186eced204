"""Import the ``vulkan`` binding with a clear error when the loader is missing."""

from __future__ import annotations

import importlib
from types import ModuleType

from rgraph.vk.errors import INSTALL_HINT, VulkanUnavailable

_vk: ModuleType | None = None


def vk() -> ModuleType:
    """The ``vulkan`` module; raises VulkanUnavailable when libvulkan cannot be loaded."""
    global _vk
    if _vk is None:
        try:
            _vk = importlib.import_module("vulkan")
        except (OSError, ImportError) as exc:
            raise VulkanUnavailable(f"cannot load the Vulkan loader ({exc}); {INSTALL_HINT}") from exc
    return _vk
