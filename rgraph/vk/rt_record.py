"""Ray tracing commands of the recording context (mixed into ``RecordContext``): trace calls
and accel builds. Like the rest of the context, no barriers: the plan synchronizes."""

from __future__ import annotations

from typing import Any

from rgraph.vk.rt_device import proc


class RayTracingCommands:
    _device: Any
    _cb: Any

    def trace_rays(self, pipeline: Any, width: int, height: int, depth: int = 1) -> None:
        """vkCmdTraceRaysKHR over ``pipeline``'s SBT (bind it first with ``bind``)."""
        rg, miss, hit, call = pipeline.regions
        proc(self._device, "vkCmdTraceRaysKHR")(self._cb, rg, miss, hit, call, int(width), int(height), int(depth))

    def trace_rays_indirect(self, pipeline: Any, indirect_address: int) -> None:
        """vkCmdTraceRaysIndirectKHR: width/height/depth (3 uint32) read at ``indirect_address``
        (a buffer with a device address, synchronized as an ``indirect`` read)."""
        rg, miss, hit, call = pipeline.regions
        proc(self._device, "vkCmdTraceRaysIndirectKHR")(self._cb, rg, miss, hit, call, int(indirect_address))

    def build_accel(self, accels: Any, name: str, set_index: int) -> None:
        """This frame's build (or refit) of plan accel ``name`` (``rgraph.vk.accel.AccelSet``)."""
        accels.record_frame_build(self._cb, name, set_index)

    def buffer_address(self, buffer: Any) -> int:
        from rgraph.vk.accel import buffer_address

        return buffer_address(self._device, buffer)
