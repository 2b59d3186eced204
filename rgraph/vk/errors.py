"""Errors raised by the Vulkan runtime."""

from __future__ import annotations


class VulkanUnavailable(RuntimeError):
    """No Vulkan loader, no ICD, or no device with the features rgraph needs."""


class ExecutionError(RuntimeError):
    """The plan cannot be executed as written (mismatched sizes, unsupported usage, ...)."""


INSTALL_HINT = (
    "install a Vulkan loader and a driver, e.g. `apt-get install libvulkan1 mesa-vulkan-drivers` "
    "(mesa-vulkan-drivers provides lavapipe, a CPU implementation)"
)
