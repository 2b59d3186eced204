"""Capture a device profile: limits, memory types/heaps, and measured memory requirements.

For each format with optimal-tiling sampled or attachment support the requirements are
measured on a grid of extents/mips/layers/samples; a size rule is fitted and verified
against every sample (``rgraph.memory_requirements.fit_image_rule``); raw samples are kept.
"""

from __future__ import annotations

from typing import Any

from rgraph import formats
from rgraph.memory_requirements import align_up, fit_block_linear_rule, fit_image_rule
from rgraph.vk.device import Device
from rgraph.vk.loader import vk
from rgraph.vk.memreq import DeviceMemoryRequirements

LIMITS = (
    "bufferImageGranularity", "maxImageDimension1D", "maxImageDimension2D", "maxImageDimension3D",
    "maxImageArrayLayers", "maxStorageBufferRange", "maxUniformBufferRange", "maxMemoryAllocationCount",
    "minStorageBufferOffsetAlignment", "minUniformBufferOffsetAlignment", "nonCoherentAtomSize",
    "maxComputeWorkGroupInvocations", "maxColorAttachments", "maxPushConstantsSize",
    "maxBoundDescriptorSets", "maxPerStageDescriptorSampledImages", "maxPerStageDescriptorStorageImages",
    "maxPerStageDescriptorStorageBuffers", "maxPerStageDescriptorUniformBuffers", "timestampPeriod",
    "framebufferColorSampleCounts", "framebufferDepthSampleCounts", "maxFramebufferWidth",
    "maxFramebufferHeight", "maxFramebufferLayers", "optimalBufferCopyRowPitchAlignment",
)

EXTENTS = [(1, 1), (3, 5), (17, 9), (64, 64), (100, 37), (255, 257), (640, 360), (1000, 17), (1920, 1080)]
MIPPED = [((64, 64), 7), ((100, 37), 3), ((255, 257), 4), ((17, 1000), 5)]
LAYERED = [((64, 64), 1, 2), ((100, 37), 3, 6), ((33, 17), 2, 3)]
BUFFER_SIZES = [1, 3, 64, 100, 255, 1000, 4096, 65537]
BUFFER_USAGES = ["uniform", "vertex", "index", "indirect", "storage_rw", "transfer_src", "transfer_dst"]

_IMAGE_USAGES = ("sampled", "color_attachment", "color_attachment_blend", "depth_attachment", "depth_read",
                 "storage_rw")


def _flag_names(value: int, prefix: str) -> list[str]:
    v = vk()
    out = []
    for name in dir(v):
        if name.startswith(prefix) and name.endswith("_BIT"):
            bit = getattr(v, name)
            if isinstance(bit, int) and bit and value & bit == bit and bin(bit).count("1") == 1:
                out.append(name.removeprefix(prefix).removesuffix("_BIT"))
    return sorted(set(out))


def _supported_usages(features: int, info: formats.FormatInfo) -> list[str]:
    v = vk()
    out = []
    if features & v.VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT:
        out.append("sampled")
    if features & v.VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT:
        out.append("color_attachment")
    if features & v.VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT:
        out.append("color_attachment_blend")
    if features & v.VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT:
        out += ["depth_attachment", "depth_read"]
    if features & v.VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT:
        out += ["storage_read", "storage_write", "storage_rw"]
    return out


def _sample_counts(device: Device, usages: list[str]) -> list[int]:
    limits = device.properties.limits
    mask = 0
    if "color_attachment" in usages:
        mask = limits.framebufferColorSampleCounts
    elif "depth_attachment" in usages:
        mask = limits.framebufferDepthSampleCounts
    return [n for n in (1, 2, 4, 8, 16) if mask & n] or [1]


def _measure_format(req: DeviceMemoryRequirements, device: Device, info: formats.FormatInfo,
                    usages: list[str]) -> dict[str, Any]:
    vk_name = info.vk_name
    counts = _sample_counts(device, usages)
    grid: list[tuple[tuple[int, int, int], int, int, int]] = [((w, h, 1), 1, 1, 1) for w, h in EXTENTS]
    grid += [((w, h, 1), mips, 1, 1) for (w, h), mips in MIPPED]
    grid += [((w, h, 1), mips, layers, 1) for (w, h), mips, layers in LAYERED]
    grid += [((w, h, 1), 1, 1, s) for s in counts if s > 1 for w, h in [(64, 64), (100, 37)]]
    minimal = ["sampled"] if "sampled" in usages else usages[:1]
    samples = []
    independent = True
    for extent, mips, layers, count in grid:
        full_usages = [u for u in usages if count == 1 or u not in ("sampled", "storage_read", "storage_write",
                                                                     "storage_rw")]
        size, alignment, bits = req.image(vk_name, extent, mips, layers, count, full_usages or minimal)
        if count == 1 and req.image(vk_name, extent, mips, layers, count, minimal) != (size, alignment, bits):
            independent = False
        samples.append([*extent, mips, layers, count, size, alignment, bits])
    alignments = {s[7] for s in samples}
    bits = {s[8] for s in samples}
    rule = (fit_image_rule([tuple(s) for s in samples], info.block_bytes, info.block_extent)
            or fit_block_linear_rule([tuple(s) for s in samples], info.block_bytes, info.block_extent))
    if len(alignments) != 1 or len(bits) != 1:
        rule = None
    return {
        "usages": usages, "usage_independent": independent, "block_bytes": info.block_bytes,
        "block_extent": list(info.block_extent), "sample_counts": counts,
        "alignment": max(alignments), "memory_type_bits": min(bits) if len(bits) == 1 else 0,
        "rule": rule, "samples": samples,
    }


class ProfileCaptureError(RuntimeError):
    """The device's requirements follow no rule a profile can describe (message says which)."""


def _size_align(pairs: list[tuple[int, int]]) -> int:
    """The smallest power of two that rounds every requested size to the measured one; 0: none."""
    return next((a for a in (1 << i for i in range(17)) if all(align_up(max(n, 1), a) == got for n, got in pairs)), 0)


def _measure_buffers(req: DeviceMemoryRequirements) -> dict[str, Any]:
    """Per usage: size rounding and alignment, fitted and verified; combinations of usages must
    take the largest of each (checked on every pair and on all usages together)."""
    by_usage: dict[str, int] = {}
    size_by_usage: dict[str, int] = {}
    bits = set()
    measured = []
    for usage in BUFFER_USAGES:
        pairs = []
        for size in BUFFER_SIZES:
            got_size, alignment, got_bits = req.buffer(size, [usage])
            measured.append([usage, size, got_size, alignment, got_bits])
            pairs.append((size, got_size))
            by_usage[usage] = max(by_usage.get(usage, 1), alignment)
            bits.add(got_bits)
        size_by_usage[usage] = _size_align(pairs)
        if not size_by_usage[usage]:
            raise ProfileCaptureError(f"buffer sizes for usage {usage} follow no power-of-two rounding: "
                                      + ", ".join(f"{n} -> {got}" for n, got in pairs))
    for usage, size, _got, alignment, _bits in measured:
        if by_usage[usage] != alignment:
            raise ProfileCaptureError(f"buffer alignment for usage {usage} depends on size ({size}: {alignment})")
    combos = [[a, b] for i, a in enumerate(BUFFER_USAGES) for b in BUFFER_USAGES[i + 1:]] + [list(BUFFER_USAGES)]
    combined = []
    for usages in combos:
        for size in (1, 100, 65537):
            got_size, alignment, got_bits = req.buffer(size, usages)
            combined.append([usages, size, got_size, alignment, got_bits])
            want_size = align_up(size, max(size_by_usage[u] for u in usages))
            want_alignment = max(by_usage[u] for u in usages)
            if (got_size, alignment) != (want_size, want_alignment) or got_bits not in bits:
                raise ProfileCaptureError(
                    f"buffer requirements for usages {'+'.join(usages)} size {size} are {got_size} bytes aligned "
                    f"{alignment}, not the largest of the single usages ({want_size}, {want_alignment})")
    if len(bits) != 1:
        raise ProfileCaptureError(f"buffer memory type bits depend on usage: {sorted(bits)}")
    return {"alignment_by_usage": by_usage, "alignment": 1, "size_align_by_usage": size_by_usage,
            "size_align": max(size_by_usage.values()), "memory_type_bits": min(bits), "samples": measured,
            "combined_samples": combined}


def capture_profile(device: Device, name: str, format_names: list[str] | None = None) -> dict[str, Any]:
    v = vk()
    req = DeviceMemoryRequirements(device)
    props = device.properties
    limits = {n: getattr(props.limits, n) for n in LIMITS}
    limits = {k: (float(x) if isinstance(x, float) else int(x)) for k, x in limits.items()}
    mem = device.memory_properties
    memory_types = [
        {"heap": int(mem.memoryTypes[i].heapIndex),
         "flags": _flag_names(mem.memoryTypes[i].propertyFlags, "VK_MEMORY_PROPERTY_")}
        for i in range(mem.memoryTypeCount)
    ]
    memory_heaps = [
        {"bytes": int(mem.memoryHeaps[i].size), "flags": _flag_names(mem.memoryHeaps[i].flags, "VK_MEMORY_HEAP_")}
        for i in range(mem.memoryHeapCount)
    ]
    format_entries: dict[str, Any] = {}
    rejected: dict[str, str] = {}
    infos = [formats.lookup(n) for n in format_names] if format_names else formats.all_formats()
    for info in infos:
        if info.is_planar or info.chroma:
            continue
        try:
            fp = v.vkGetPhysicalDeviceFormatProperties(device.physical.handle, info.value)
        except Exception:  # noqa: BLE001 -- formats unknown to this driver
            continue
        usages = _supported_usages(fp.optimalTilingFeatures, info)
        if not {"sampled", "color_attachment", "depth_attachment"} & set(usages):
            continue
        entry = _measure_format(req, device, info, usages)
        if entry["rule"] is None:
            rejected[info.vk_name] = "no rule of the supported family predicts every sample; samples only"
        format_entries[info.vk_name] = entry
    api = props.apiVersion
    extra: dict[str, Any] = {}
    if "accelerationStructure" in device.enabled_features:
        from rgraph.vk.accel_capture import capture_accel

        extra["accel"] = capture_accel(device)
    return {
        **extra,
        "format": "rgraph-device-profile/1",
        "name": name,
        "device": device.name,
        "device_type": device.physical.device_type,
        "vendor_id": int(props.vendorID), "device_id": int(props.deviceID),
        "driver_version": int(props.driverVersion),
        "api_version": [api >> 22, (api >> 12) & 0x3FF, api & 0xFFF],
        "runtime_usages": ["transfer_src", "transfer_dst"],
        "limits": limits,
        "memory_types": memory_types,
        "memory_heaps": memory_heaps,
        "buffer": _measure_buffers(req),
        "formats": format_entries,
        "rules_rejected": rejected,
    }
