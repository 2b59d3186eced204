"""``rgraph devices``: the physical devices ``--device`` / ``--devices`` index."""

from __future__ import annotations

import argparse
import os
import sys


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("devices", help="list the Vulkan physical devices (indices for --device/--devices)")
    parser.set_defaults(func=run)


def _extensions(handle) -> set[str]:
    from rgraph.vk.loader import vk

    v = vk()
    return {p.extensionName if isinstance(p.extensionName, str) else v.ffi.string(p.extensionName).decode()
            for p in v.vkEnumerateDeviceExtensionProperties(handle, None)}


def run(args: argparse.Namespace) -> int:
    from rgraph.vk.device import list_physical_devices
    from rgraph.vk.errors import VulkanUnavailable
    from rgraph.vk.instance import create_instance
    from rgraph.vk.multi.run import HOST_IMPORT

    try:
        instance = create_instance(False)
    except VulkanUnavailable as exc:
        print(f"rgraph: error: {exc}", file=sys.stderr)
        return 2
    try:
        devices = list_physical_devices(instance)
        for d in devices:
            host = "yes" if HOST_IMPORT in _extensions(d.handle) else "no"
            api = ".".join(str(n) for n in d.api_version)
            print(f"{d.index}: {d.name} ({d.device_type}, Vulkan {api}, {HOST_IMPORT}: {host})")
        if not devices:
            print("rgraph: no Vulkan physical devices", file=sys.stderr)
        print(_validation_layer_line(), file=sys.stderr)
    finally:
        instance.destroy()
    return 0 if devices else 2


def _validation_layer_line() -> str:
    """Which Khronos validation layer ``--validate`` would load, and from where."""
    from rgraph.vk.bundled_layer import bundled_layer_dir
    from rgraph.vk.instance import validation_layer_version

    version = validation_layer_version()
    if version is None:
        return "rgraph: --validate: no Khronos validation layer found (apt-get install vulkan-validationlayers)"
    where = os.environ.get("VK_LAYER_PATH") or str(bundled_layer_dir() or "the system's layer directories")
    return f"rgraph: --validate uses Khronos validation layer {'.'.join(map(str, version))} ({where})"
