"""GPU-driven drawing (``draw.mode=gpu``, ``rgraph.vk.scene_modes``): ``draw_reset`` and ``draw_cull``.

The graph buffer ``draw_args`` holds the draw count at offset 0 and VkDrawIndexedIndirectCommands
from offset 16. ``draw_reset`` (one workgroup) zeroes the count; ``draw_cull`` (one thread per
instance, ``shaders/scene/cull.comp``) emits a command for every instance whose bounding sphere
meets some view's frustum. Param ``draw.order``: ``none`` appends them in atomic order
(``16 + ${scene.draws} * 20`` bytes suffice); ``front_to_back`` orders them by distance bucket,
nearest first (``16 + ${scene.draws} * 28 + 1024`` bytes: the buckets' counts and each
instance's bucket and rank after the commands; NumPy reference ``rgraph.scene.instances.draw_buckets``).
The raster passes
read ``draw_args`` as ``indirect`` and draw it with one ``vkCmdDrawIndexedIndirectCount``
(``SceneGPU.draw(..., args=...)``). In the other draw modes both record nothing. NumPy
reference: ``rgraph.scene.instances.visible``.
"""

from __future__ import annotations

from typing import Any

from rgraph.impl import PassImpl, register
from rgraph.vk import dispatch
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


ORDERS = ("none", "front_to_back")
BUCKETS = 256  # cull.comp's distance buckets (draw.order=front_to_back)
GROUP = 256  # cull.comp's workgroup size
ORDERED_SCRATCH_BYTES = 4 * BUCKETS  # the buckets' counts
ORDERED_BYTES_PER_DRAW = COMMAND_BYTES + 8  # command, bucket, rank


def draw_order(setup: PassSetup) -> str:
    order = str(setup.param("draw.order", "none"))  # graphs without the param keep the old buffer size
    if order not in ORDERS:
        raise ExecutionError(f"pass {setup.name!r}: draw.order must be one of {', '.join(ORDERS)}, got {order!r}")
    return order


def command_capacity(size: int, order: str) -> int:
    """Commands a ``draw_args`` buffer of ``size`` bytes holds under ``order``."""
    if order == "none":
        return (size - HEADER_BYTES) // COMMAND_BYTES
    return max(0, size - HEADER_BYTES - ORDERED_SCRATCH_BYTES) // ORDERED_BYTES_PER_DRAW


class _DrawArgsPass(PassImpl):
    reset = 0

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.scene = setup.scene
        self.active = self.scene.mode == "gpu"
        order = draw_order(setup)
        _handle, size = setup.buffer("draw_args", 0)
        self.capacity = command_capacity(size, order)
        if self.active and self.capacity < self.scene.draw_count:
            need = "16 + ${scene.draws} * 20" if order == "none" else "16 + ${scene.draws} * 28 + 1024"
            raise ExecutionError(f"pass {setup.name!r}: draw_args holds {self.capacity} commands, the scene has "
                                 f"{self.scene.draw_count} draws (size it {need} for draw.order={order})")
        if not self.active:
            return
        self.sets = setup.descriptors([Binding(0, "storage_buffer", "draw_args")])
        self.pipeline = setup.compute_pipeline("scene/cull.comp", [self.scene.set_layout, self.sets.layout],
                                               defines={"RESET": self.reset, "ORDERED": int(order != "none")},
                                               push_constant_bytes=8)
        self.push = pack("2I", self.scene.draw_count, self.capacity)
        self.groups = (1, 1) if self.reset else dispatch.groups_2d(self.scene.draw_count, GROUP)

    def record(self, rec, frame_set: int) -> None:
        if not self.active:
            return
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups, 1)


@register("draw_reset")
class DrawReset(_DrawArgsPass):
    """Zeroes the draw count of ``draw_args`` (see the module docstring)."""
    reset = 1


@register("draw_cull")
class DrawCull(_DrawArgsPass):
    """Frustum-culls every instance into ``draw_args`` (see the module docstring)."""
