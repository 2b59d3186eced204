"""Capture acceleration-structure sizes for a device profile (``rgraph device-profile``).

Measures vkGetAccelerationStructureBuildSizesKHR for triangle BLAS and instance TLAS over
``rgraph.accel_profile.CAPTURE_COUNTS`` (BLAS at two vertex counts, to see whether sizes
depend on them), with and without updates, and fits the rules of ``rgraph.accel_profile``.
"""

from __future__ import annotations

from typing import Any

from rgraph.accel_profile import CAPTURE_COUNTS, fit_level
from rgraph.memory_requirements import align_up
from rgraph.vk.accel_sizes import query
from rgraph.vk.device import Device
from rgraph.vk.memreq import DeviceMemoryRequirements
from rgraph.vk.rt_device import properties

_BUFFER_SIZES = (1, 100, 4096, 65537, 1 << 20)


def _buffer_rule(req: DeviceMemoryRequirements, usage: str) -> dict[str, int]:
    got = [req.buffer(n, [usage]) for n in _BUFFER_SIZES]
    alignment = {a for _, a, _ in got}
    bits = {b for _, _, b in got}
    size_align = next((a for a in (1 << i for i in range(17))
                       if all(align_up(n, a) == s for n, (s, _, _) in zip(_BUFFER_SIZES, got, strict=True))), 0)
    if len(alignment) != 1 or len(bits) != 1 or not size_align:
        from rgraph.vk.profile_capture import ProfileCaptureError

        raise ProfileCaptureError(f"buffer requirements for usage {usage} follow no rule: {got}")
    return {"alignment": alignment.pop(), "size_align": size_align, "memory_type_bits": bits.pop()}


def capture_accel(device: Device) -> dict[str, Any]:
    req = DeviceMemoryRequirements(device)
    levels: dict[str, Any] = {}
    for level in ("bottom", "top"):
        samples = []
        for count in CAPTURE_COUNTS:
            vertex_counts = (3 * count - 1, max(count // 2, 2)) if level == "bottom" else (0,)
            for max_vertex in vertex_counts:
                for update in (False, True):
                    samples.append([count, max_vertex, int(update), *query(device, level, count, max_vertex, update)])
        levels[level] = {"samples": samples, "rules": fit_level(samples)}
    return {
        "scratch_alignment": properties(device.physical.handle).min_scratch_offset_alignment,
        "buffer": {u: _buffer_rule(req, u) for u in ("accel_storage", "accel_scratch", "trace_indirect")},
        **levels,
    }
