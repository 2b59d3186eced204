"""Plan names (sync2 without prefixes/suffixes, usage words, formats) -> Vulkan enum values."""

from __future__ import annotations

from collections.abc import Iterable
from functools import cache

from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk

#: Usages the runtime always adds: readback of outputs (transfer_src) and initialisation of
#: persistent/imported resources (transfer_dst). Memory-requirement providers add them too,
#: so the plan's sizes match what the runtime creates.
WHOLE_SIZE = 0xFFFFFFFFFFFFFFFF  # VK_WHOLE_SIZE (the binding exposes it as -1)

RUNTIME_USAGES = ("transfer_src", "transfer_dst")

_IMAGE_USAGE = {
    "color_attachment": "COLOR_ATTACHMENT", "color_attachment_blend": "COLOR_ATTACHMENT",
    "depth_attachment": "DEPTH_STENCIL_ATTACHMENT", "depth_read": "DEPTH_STENCIL_ATTACHMENT",
    "sampled": "SAMPLED", "storage_read": "STORAGE", "storage_write": "STORAGE", "storage_rw": "STORAGE",
    "transfer_src": "TRANSFER_SRC", "transfer_dst": "TRANSFER_DST",
}
_BUFFER_USAGE = {
    "uniform": "UNIFORM_BUFFER", "vertex": "VERTEX_BUFFER", "index": "INDEX_BUFFER",
    "indirect": "INDIRECT_BUFFER", "storage_read": "STORAGE_BUFFER", "storage_write": "STORAGE_BUFFER",
    "storage_rw": "STORAGE_BUFFER", "transfer_src": "TRANSFER_SRC", "transfer_dst": "TRANSFER_DST",
    "accel_storage": "ACCELERATION_STRUCTURE_STORAGE_BIT_KHR|0x20000",
    "accel_build": "ACCELERATION_STRUCTURE_STORAGE_BIT_KHR|0x20000",
    "accel_read": "ACCELERATION_STRUCTURE_STORAGE_BIT_KHR|0x20000",
    "accel_scratch": "STORAGE_BUFFER|0x20000",
    "trace_indirect": "INDIRECT_BUFFER|0x20000",
}
SHADER_DEVICE_ADDRESS = 0x20000  # VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT (core 1.2)
MEMORY_ALLOCATE_DEVICE_ADDRESS = 0x2  # VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT
#: Buffer usages whose memory must be allocated with VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT.
DEVICE_ADDRESS_USAGES = frozenset({"accel_storage", "accel_build", "accel_read", "accel_scratch", "trace_indirect"})


def _const(name: str) -> int:
    try:
        return int(getattr(vk(), name))
    except AttributeError:
        raise ExecutionError(f"unknown Vulkan name {name}") from None


def _bit_name(prefix: str, name: str) -> str:
    """``RAY_TRACING_SHADER_KHR`` -> ``..._RAY_TRACING_SHADER_BIT_KHR`` (vendor suffix after BIT)."""
    for suffix in ("_KHR", "_EXT", "_NV"):
        if name.endswith(suffix):
            return f"{prefix}{name[:-len(suffix)]}_BIT{suffix}"
    return f"{prefix}{name}_BIT"


@cache
def stage(name: str) -> int:
    if name == "NONE":
        return 0
    return _const(_bit_name("VK_PIPELINE_STAGE_2_", name))


@cache
def access(name: str) -> int:
    if name == "NONE":
        return 0
    return _const(_bit_name("VK_ACCESS_2_", name))


@cache
def layout(name: str) -> int:
    return _const(f"VK_IMAGE_LAYOUT_{name}")


@cache
def format_value(name: str) -> int:
    from rgraph.formats import lookup

    try:
        return lookup(name).value
    except KeyError:
        raise ExecutionError(f"unknown format {name}") from None


def stages(names: Iterable[str]) -> int:
    out = 0
    for n in names:
        out |= stage(n)
    return out


def accesses(names: Iterable[str]) -> int:
    out = 0
    for n in names:
        out |= access(n)
    return out


def image_usage(usages: Iterable[str]) -> int:
    out = 0
    for u in set(usages) | set(RUNTIME_USAGES):
        if u not in _IMAGE_USAGE:
            raise ExecutionError(f"usage {u!r} does not apply to images")
        out |= _const(f"VK_IMAGE_USAGE_{_IMAGE_USAGE[u]}_BIT")
    return out


def buffer_usage(usages: Iterable[str]) -> int:
    out = 0
    for u in set(usages) | set(RUNTIME_USAGES):
        if u not in _BUFFER_USAGE:
            raise ExecutionError(f"usage {u!r} does not apply to buffers")
        for bit in _BUFFER_USAGE[u].split("|"):
            if bit.startswith("0x"):  # the binding lacks VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT
                out |= int(bit, 16)
            else:
                out |= _const(f"VK_BUFFER_USAGE_{bit}" if bit.endswith("_KHR") else f"VK_BUFFER_USAGE_{bit}_BIT")
    return out


def sample_count(samples: int) -> int:
    return _const(f"VK_SAMPLE_COUNT_{int(samples)}_BIT")


def aspect_mask(format_name: str) -> int:
    from rgraph.formats import lookup

    info = lookup(format_name)
    v = vk()
    mask = 0
    if info.has_depth:
        mask |= v.VK_IMAGE_ASPECT_DEPTH_BIT
    if info.has_stencil:
        mask |= v.VK_IMAGE_ASPECT_STENCIL_BIT
    return mask or v.VK_IMAGE_ASPECT_COLOR_BIT
