"""Import the ``vulkan`` binding with a clear error when the loader is missing."""

from __future__ import annotations

import importlib
from types import ModuleType

from rgraph.vk import enum_fixes
from rgraph.vk.errors import INSTALL_HINT, VulkanUnavailable

_vk: ModuleType | None = None


def vk() -> ModuleType:
    """The ``vulkan`` module, its wrong enum values corrected (:mod:`rgraph.vk.enum_fixes`); raises VulkanUnavailable when libvulkan cannot be loaded."""
    global _vk
    if _vk is None:
        try:
            module = importlib.import_module("vulkan")
        except (OSError, ImportError) as exc:
            raise VulkanUnavailable(f"cannot load the Vulkan loader ({exc}); {INSTALL_HINT}") from exc
        enum_fixes.apply(module)
        _vk = module
    return _vk
