"""GPU-driven drawing (``draw.mode=gpu``, ``rgraph.vk.scene_modes``): ``draw_reset`` and ``draw_cull``.

The graph buffer ``draw_args`` (``16 + ${scene.draws} * 20`` bytes) holds the draw count at
offset 0 and VkDrawIndexedIndirectCommands from offset 16. ``draw_reset`` (one thread) zeroes
the count; ``draw_cull`` (one thread per instance, ``shaders/scene/cull.comp``) appends a
command for every instance whose bounding sphere meets some view's frustum; the raster passes
read ``draw_args`` as ``indirect`` and draw it with one ``vkCmdDrawIndexedIndirectCount``
(``SceneGPU.draw(..., args=...)``). In the other draw modes both record nothing. NumPy
reference: ``rgraph.scene.instances.visible``.
"""

from __future__ import annotations

from typing import Any

from rgraph.impl import PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, PassSetup, pack

COMMAND_BYTES = 20
HEADER_BYTES = 16


def draw_args(setup: PassSetup, frame_set: int) -> Any:
    """The ``draw_args`` buffer a raster pass reads as ``indirect`` (None: no such read, or
    the scene is not drawn GPU-driven)."""
    if not setup.has("draw_args") or setup.scene.mode != "gpu":
        return None
    return setup.buffer("draw_args", frame_set)[0]


class _DrawArgsPass(PassImpl):
    reset = 0

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.scene = setup.scene
        self.active = self.scene.mode == "gpu"
        _handle, size = setup.buffer("draw_args", 0)
        self.capacity = (size - HEADER_BYTES) // COMMAND_BYTES
        if self.active and self.capacity < self.scene.draw_count:
            raise ExecutionError(f"pass {setup.name!r}: draw_args holds {self.capacity} commands, the scene has "
                                 f"{self.scene.draw_count} draws (size it 16 + ${{scene.draws}} * 20)")
        if not self.active:
            return
        self.sets = setup.descriptors([Binding(0, "storage_buffer", "draw_args")])
        self.pipeline = setup.compute_pipeline("scene/cull.comp", [self.scene.set_layout, self.sets.layout],
                                               defines={"RESET": self.reset}, push_constant_bytes=8)

    def record(self, rec, frame_set: int) -> None:
        if not self.active:
            return
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, pack("2I", self.scene.draw_count, self.capacity))
        rec.dispatch(1 if self.reset else max(1, -(-self.scene.draw_count // 64)), 1, 1)


@register("draw_reset")
class DrawReset(_DrawArgsPass):
    """Zeroes the draw count of ``draw_args`` (see the module docstring)."""
    reset = 1


@register("draw_cull")
class DrawCull(_DrawArgsPass):
    """Frustum-culls every instance into ``draw_args`` (see the module docstring)."""
