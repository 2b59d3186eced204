"""draw.mode=naive's per-frame tables on the GPU: host-written, copied to device memory per frame.

Two ways to draw (graph param ``draw.naive``):

- ``direct`` (default): the engines' way. Per frame the CPU culls every object
  (``rgraph.scene.instances.naive_visible``, kept in ``visible[set]``) and the frame's command
  buffers are recorded again with one ``vkCmdDrawIndexed`` per visible object
  (``SceneGPU.rerecord``, ``rgraph.vk.runtime.commands.rerecord``): the recording is the CPU
  cost an engine pays per frame, and no indirect command is read.
- ``indirect``: command buffers recorded once with one ``vkCmdDrawIndexedIndirect`` per object,
  reading per-set CPU-written commands (instanceCount 0 when culled). It lost the device on an
  NVIDIA H200 with vr_instanced (32,768 indirect draws per pass, sessions 7-9; lavapipe with
  GPU-assisted validation found no fault at 8,000 objects), hence the default.

Per frame-in-flight set, host-visible buffers the CPU writes every frame
(``rgraph.vk.scene_frame``: every object's camera-relative Draw, 144 bytes, and with
``indirect`` its VkDrawIndexedIndirectCommand, 20 bytes), and device-local copies the frame's
draws read: the vertex and fragment shaders' Draws (set 0, binding 1) and the indirect commands.
``record(cb, s)`` goes at the start of the frame's first scene batch on the graphics queue
(``SceneGPU.record_frame``, before any draw of the frame): a barrier (the previous frame of
this set's draws have read the device copies: write-after-read), one vkCmdCopyBuffer per
table, a barrier (copy writes before indirect-command and shader reads).

Why copies: the GPU then never reads a table the CPU is writing (each set's host buffers
are written only after its fence, the copy runs in queue order before the frame's draws), and
the front end fetches its 32,768 indirect commands from device memory instead of across the
bus (``--naive-cpu`` lost the device on an NVIDIA H200 with host-memory commands, session 7).
"""

from __future__ import annotations

from bisect import bisect_left
from typing import Any

from rgraph.vk.device_local import barrier
from rgraph.vk.loader import vk

COMMAND_BYTES = 20  # VkDrawIndexedIndirectCommand


class NaiveTables:
    """See the module docstring. ``draws_size``: bytes of the Draws table; ``draw_count``:
    objects (one command each). ``device_buffer(size, usage)`` and ``host_buffer(size, usage)``
    come from ``SceneGPU`` (it owns and destroys the buffers)."""

    def __init__(self, sets: int, draws_size: int, draw_count: int, *, device_buffer: Any, host_buffer: Any,
                 direct: bool = True) -> None:
        v = vk()
        src = v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT
        self.direct = direct
        self.draws_size = draws_size
        self.commands_size = 0 if direct else max(draw_count, 1) * COMMAND_BYTES
        self.host_draws = [host_buffer(draws_size, src) for _ in range(sets)]
        self.draws = [device_buffer(draws_size, v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT) for _ in range(sets)]
        self.host_commands = [] if direct else [host_buffer(self.commands_size, src) for _ in range(sets)]
        self.commands = [] if direct else [device_buffer(self.commands_size, v.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT)
                                           for _ in range(sets)]
        self.visible: list[list[int]] = [[] for _ in range(sets)]  # direct: per set, the CPU-visible draw ids
        self.recorded = [False] * sets  # per set: the copies are in its command buffers

    def record(self, cb: Any, frame_set: int) -> None:
        v = vk()
        pairs = [(self.host_draws[frame_set], self.draws[frame_set], self.draws_size)]
        if not self.direct:
            pairs.append((self.host_commands[frame_set], self.commands[frame_set], self.commands_size))
        outputs = [device.handle for _host, device, _size in pairs]
        readers = (v.VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | v.VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT
                   | v.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | v.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT)
        copy, write = v.VK_PIPELINE_STAGE_2_COPY_BIT, v.VK_ACCESS_2_TRANSFER_WRITE_BIT
        barrier(cb, outputs, readers, 0, copy, write)
        for host, device, size in pairs:
            v.vkCmdCopyBuffer(cb, host.handle, device.handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0, size=size)])
        barrier(cb, outputs, copy, write, readers,
                v.VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT | v.VK_ACCESS_2_SHADER_STORAGE_READ_BIT)
        self.recorded[frame_set] = True

    def draw(self, rec: Any, call: Any, frame_set: int) -> None:
        """One draw per object of ``call`` (a ``SceneGPU`` DrawCall): ``direct``, one
        vkCmdDrawIndexed per object of set ``frame_set``'s visible ids in the call's range;
        ``indirect``, one vkCmdDrawIndexedIndirect per object (its command at ``20 d``)."""
        first, end = call.first_instance, call.first_instance + call.instances
        if not self.direct:
            commands = self.commands[frame_set].handle
            for d in range(first, end):
                rec.draw_indexed_indirect(commands, COMMAND_BYTES * d)
            return
        ids = self.visible[frame_set]
        lo, hi = bisect_left(ids, first), bisect_left(ids, end)
        rec.draw_indexed_each(call.index_count, call.first_index, call.vertex_offset, ids[lo:hi])
