"""Command buffers: one per batch of the lowered recording and frame-in-flight set, recorded once (or per frame: ``rerecord``).

Per pass: a debug label, the reset of its two timestamp queries (on graphics and compute
queue families; a pass on a transfer-only family leaves ``ex.host_query_reset`` set and the
frame loop resets the set's pool from the host), a start timestamp, (the first scene pass on
the graphics queue: the scene's per-frame GPU work, ``SceneGPU.record_frame``: deformable
vertices, naive mode's table copies), the pass's lowered barrier calls, its commands
(``ImplPass.record``), its lowered releases, an end timestamp. Nothing here decides a
barrier (``rgraph.vk.lower``); ``rgraph.vk.record`` builds the structs.
"""

from __future__ import annotations

from typing import Any

from rgraph.vk.debug_names import name_object
from rgraph.vk.loader import vk
from rgraph.vk.record import barrier_batches
from rgraph.vk.record_context import RecordContext
from rgraph.vk.runtime.setup import FRAMES_IN_FLIGHT, pool


def record(ex: Any) -> None:
    """Allocate and record every frame-in-flight set's command buffers (once per run)."""
    ex.command_buffers = []
    ex.host_query_reset = False
    ex.barrier_batches_of = {}
    for s in range(FRAMES_IN_FLIGHT):
        ex.command_buffers.append(record_set(ex, s, None))


def rerecord(ex: Any, s: int) -> None:
    """Record set ``s``'s command buffers again (its fences have signalled): its command pools
    are reset and the same handles recorded anew, so the prebuilt submits stay valid. The
    frame loop calls it per frame when the scene's draws change per frame
    (``SceneGPU.rerecord``: draw.mode=naive's direct draws of the CPU-visible objects)."""
    v = vk()
    for family in sorted({ex.device.families[b.queue] for b in ex.recording.batches}):
        v.vkResetCommandPool(ex.device.handle, pool(ex, family, s), 0)
    record_set(ex, s, ex.command_buffers[s])


def record_set(ex: Any, s: int, buffers: list[Any] | None) -> list[Any]:
    """Record set ``s``'s batches into ``buffers`` (None: allocate them); returns them."""
    v = vk()
    dev = ex.device
    recording = ex.recording
    plan_passes = ex.plan["passes"]
    deform_batch = scene_batch(ex)
    # per pass: (barrier batches before, after), built once per set; re-recording reuses them
    structs = ex.barrier_batches_of.get(s)
    if structs is None:
        structs = ex.barrier_batches_of[s] = {
            i: (barrier_batches(ex.resources, s, lowered.before), barrier_batches(ex.resources, s, lowered.after))
            for i, lowered in enumerate(recording.passes)}
    per_batch = []
    for bi, batch in enumerate(recording.batches):
        if buffers is None:
            cb = v.vkAllocateCommandBuffers(dev.handle, v.VkCommandBufferAllocateInfo(
                commandPool=pool(ex, dev.families[batch.queue], s), level=v.VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                commandBufferCount=1))[0]
            names = [plan_passes[i]["name"] for i in batch.passes]
            label = (f"pass {names[0]} (set {s})" if len(names) == 1 else f"batch {bi} (set {s}): " + ",".join(names))
            name_object(dev, cb, v.VK_OBJECT_TYPE_COMMAND_BUFFER, label)
        else:
            cb = buffers[bi]
        per_batch.append(cb)
        v.vkBeginCommandBuffer(cb, v.VkCommandBufferBeginInfo())
        ctx = RecordContext(dev, cb)
        timestamps = dev.timestamp_valid_bits.get(batch.queue, 0) > 0
        in_command_buffer = bool(dev.capabilities.get(batch.queue, frozenset()) & {"graphics", "compute"})
        ex.host_query_reset |= timestamps and not in_command_buffer
        for i in batch.passes:
            lowered = recording.passes[i]
            ex.log.context = f"recording pass {lowered.name}"
            label_begin(dev, cb, f"pass {lowered.name}")
            if timestamps:
                if in_command_buffer:  # query commands of one queue run in submission order
                    v.vkCmdResetQueryPool(cb, ex.query_pools[s], 2 * i, 2)
                v.vkCmdWriteTimestamp2(cb, v.VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, ex.query_pools[s], 2 * i)
            if bi == deform_batch and i == batch.passes[0]:  # counted in this pass's GPU time
                ex.scene_gpu.record_frame(cb, s)
            before, after = structs[i]
            for barriers in before:
                v.vkCmdPipelineBarrier2(cb, barriers.dependency)
            ex.passes[i].record(ctx, s)
            for releases in after:
                v.vkCmdPipelineBarrier2(cb, releases.dependency)
            if timestamps:
                v.vkCmdWriteTimestamp2(cb, v.VK_PIPELINE_STAGE_2_BOTTOM_OF_PIPE_BIT, ex.query_pools[s], 2 * i + 1)
            label_begin(dev, cb, None)
        v.vkEndCommandBuffer(cb)
    return per_batch


def scene_batch(ex: Any) -> int | None:
    """The first batch (submit order) on the graphics VkQueue with a pass that uses the scene:
    the scene's per-frame compute work (``SceneGPU.record_frame``) goes at its start."""
    if ex.scene_gpu is None:
        return None
    graphics = ex.device.queues["graphics"]
    for bi, batch in enumerate(ex.recording.batches):
        if ex.device.queues[batch.queue] == graphics and any(ex.passes[i].setup.uses_scene for i in batch.passes):
            return bi
    return None


def label_begin(device: Any, cb: Any, text: str | None) -> None:
    """Begin a debug label (``text``), or end the open one (None)."""
    v = vk()
    if text is None:
        fn = device.fn("vkCmdEndDebugUtilsLabelEXT")
        if fn:
            fn(cb)
        return
    fn = device.fn("vkCmdBeginDebugUtilsLabelEXT")
    if fn:
        fn(cb, v.VkDebugUtilsLabelEXT(pLabelName=text, color=[0.0, 0.0, 0.0, 0.0]))
