"""Recording: plan barriers as prebuilt sync2 structs, and the pass recording context.

``RecordContext`` is what pass implementations get: draws, dispatches, copies, binds and
push constants. It has no barrier calls: the graph owns synchronization.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence, Set
from dataclasses import dataclass, field, replace
from typing import Any

from rgraph.stages import CAPABILITIES, fit_to_queue
from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.loader import vk
from rgraph.vk.resources import ResourceSet
from rgraph.vk.rt_record import RayTracingCommands


def _aspect_for_layout(format_name: str, layout: str) -> int:
    v = vk()
    if layout.startswith("DEPTH_") and not layout.startswith("DEPTH_STENCIL") and "STENCIL" not in layout:
        return v.VK_IMAGE_ASPECT_DEPTH_BIT
    if layout.startswith("STENCIL_"):
        return v.VK_IMAGE_ASPECT_STENCIL_BIT
    return names.aspect_mask(format_name)


@dataclass(frozen=True)
class BarrierSpec:
    """One VkImageMemoryBarrier2 / VkBufferMemoryBarrier2 in plan names (pure data, no Vulkan);
    with ``resource`` None, a global VkMemoryBarrier2 (``rgraph.vk.packed_ranges``).

    ``src_family``/``dst_family``: a queue family index, or None for VK_QUEUE_FAMILY_IGNORED.
    ``aspect_layout``: the layout that picks the image aspect (the plan barrier's dst layout,
    else its src layout), so that every struct derived from one plan barrier names one aspect.
    """

    resource: str | None
    subresource: dict | None
    src_stages: tuple[str, ...]
    src_access: tuple[str, ...]
    dst_stages: tuple[str, ...]
    dst_access: tuple[str, ...]
    old_layout: str | None
    new_layout: str | None
    src_family: int | None = None
    dst_family: int | None = None
    aspect_layout: str | None = None


def lower_barriers(barriers: list[dict], role: str, families: Mapping[str, int],
                   wait_stages: Sequence[str] = (),
                   capabilities: frozenset[str] = CAPABILITIES,
                   writers: Mapping[int, tuple[str, ...]] | None = None,
                   partial_handoffs: Set[int] = frozenset()) -> list[list[BarrierSpec]]:
    """Plan barriers -> the vkCmdPipelineBarrier2 calls that execute them, in recording order.

    ``role`` is "barrier" (before the pass) or "release" (after it); ``families`` maps plan
    queues to queue family indices. Each inner list is one vkCmdPipelineBarrier2 (barriers in
    one call are not ordered with each other; consecutive calls are, through their stages).

    - Ordinary barriers (one queue) are one struct each, queue families IGNORED.
    - An ownership pair whose two plan queues share a family: the release is skipped and the
      acquire point executes one ordinary barrier (the semaphore orders the queues).
    - A queue-family ownership transfer between distinct families carries NO layout change:
      the release (source queue) and the acquire (destination queue) both keep the source
      layout (oldLayout == newLayout), and the layout change is a separate ordinary barrier
      recorded on the destination queue right after the acquire (a second call, its src scope
      the acquire's dst stages, so the two chain). The acquire's src stages are its own dst
      stages: they are the stages the pass's semaphore wait covers (the plan's wait stages hold
      every stage of the pass's accesses that wait for another queue), so the acquire chains to
      the wait and happens after the release. With src stages NONE (as before) the acquire and
      its layout transition were ordered after nothing on the destination queue: syncval
      reported the acquire's transition racing the release's (WRITE_RACING_WRITE), the reads
      after it racing the release (READ_RACING_WRITE), and the acquire's transition racing the
      previous frame's reads on the destination queue (WRITE_AFTER_READ). Keeping the layout
      out of the pair also keeps a layer that does not model ownership transfers (1.3.239,
      DESIGN.md) from counting one transition twice; release/acquire access masks follow the
      spec (release: no dst access, acquire: no src access).
    - A layout transition after reads names MEMORY_READ as its src access (``_after_reads``).
      Any ordinary barrier after reads whose write ``writers`` (barrier index -> stages,
      ``rgraph.vk.after_reads``) knows names that write too: its stages and MEMORY_WRITE.
    - ``wait_stages``: the stages of the pass's semaphore waits on another VkQueue. Every
      barrier before the pass with a src scope adds them to its src stages, so it chains to
      the wait: a plan barrier's src stages may name another queue's stages (an aliased
      resource's previous occupant read on the compute queue, say), which on this queue are
      ordered after nothing the semaphore covers (an H100 run: WRITE_AFTER_READ in forward).
    - ``partial_handoffs``: indices of aliasing hand-offs the 1.3.239 layer sees only in part
      (``rgraph.vk.packed_ranges``): each also gets a global memory barrier with its src scope
      and dst ALL_COMMANDS / MEMORY_READ|MEMORY_WRITE, in the same call.
    - ``capabilities``: what the recording queue's family does (graphics/compute/transfer).
      Stages it does not run, and the accesses only they perform, are dropped from both
      scopes (``rgraph.stages.fit_to_queue``): a release on a compute-only family after
      reads on the graphics queue names INDEX_INPUT in the plan, which that family rejects
      (VUID-vkCmdPipelineBarrier2-srcStageMask-03849, H100 fuzz seed 48).
    """
    first: list[BarrierSpec] = []
    after: list[BarrierSpec] = []
    chain = tuple(sorted(set(wait_stages)))
    for index, b in enumerate(barriers):
        for group, spec in _lower_one(b, role, families):
            if chain and group == 0 and spec.src_stages and spec.src_family is None:
                spec = replace(spec, src_stages=tuple(sorted(set(spec.src_stages) | set(chain))))
            spec = _name_read_write(spec, (writers or {}).get(index, ()))
            if capabilities != CAPABILITIES:
                spec = _fit(spec, capabilities)
            spec = _after_reads(spec)
            (first if group == 0 else after).append(spec)
            if index in partial_handoffs and group == 0 and spec.src_stages:
                first.append(_global_after(spec))
    return [group for group in (first, after) if group]


#: dst scope of the global barrier that completes a partly seen hand-off: every later command.
GLOBAL_DST_STAGES = ("ALL_COMMANDS",)
GLOBAL_DST_ACCESS = ("MEMORY_READ", "MEMORY_WRITE")


def _global_after(spec: BarrierSpec) -> BarrierSpec:
    """A global memory barrier with ``spec``'s src scope, ordering it before every later command."""
    return BarrierSpec(None, None, spec.src_stages, spec.src_access, GLOBAL_DST_STAGES, GLOBAL_DST_ACCESS,
                       None, None)


def _fit(spec: BarrierSpec, capabilities: frozenset[str]) -> BarrierSpec:
    src_stages, src_access = fit_to_queue(spec.src_stages, spec.src_access, capabilities)
    dst_stages, dst_access = fit_to_queue(spec.dst_stages, spec.dst_access, capabilities)
    return replace(spec, src_stages=src_stages, src_access=src_access, dst_stages=dst_stages, dst_access=dst_access)


#: srcAccessMask of a layout transition that follows reads (see ``_after_reads``); with the
#: write those reads read, when it is known (``_name_read_write``).
AFTER_READS_ACCESS = ("MEMORY_READ",)
AFTER_WRITE_READS_ACCESS = ("MEMORY_READ", "MEMORY_WRITE")


def _is_transition_after_reads(spec: BarrierSpec) -> bool:
    return (spec.old_layout is not None and spec.old_layout != spec.new_layout and bool(spec.src_stages)
            and not spec.src_access)


def _name_read_write(spec: BarrierSpec, write_stages: tuple[str, ...]) -> BarrierSpec:
    """An ordinary barrier after reads (src stages, no src access) whose reads read a write
    with stages ``write_stages`` (``rgraph.vk.after_reads``, which says why the 1.3.239 layer
    needs it) also names that write in its src scope: its stages and MEMORY_READ|MEMORY_WRITE
    (a repeated availability operation for a write already available, a no-op by the spec).
    Layout transitions and buffer or same-layout barriers before a write alike. A transition
    from UNDEFINED (aliased memory after the previous occupant's reads) gets the stages only
    (``_after_reads`` names MEMORY_READ); ownership transfers keep their spec-mandated masks."""
    if (write_stages and spec.src_stages and not spec.src_access and spec.src_family is None
            and spec.dst_family is None):
        stages = tuple(sorted(set(spec.src_stages) | set(write_stages)))
        if spec.old_layout == "UNDEFINED":  # aliased memory: the stages only, _after_reads names MEMORY_READ
            return replace(spec, src_stages=stages)
        return replace(spec, src_stages=stages, src_access=AFTER_WRITE_READS_ACCESS)
    return spec


def _after_reads(spec: BarrierSpec) -> BarrierSpec:
    """A layout transition whose src scope is reads only (src stages, no src access) gets
    srcAccessMask MEMORY_READ. By the spec this is a no-op: availability operations concern
    writes, the write before those reads was made available by the barrier in front of them,
    and the transition is ordered after it through the reads' stages (an execution chain).
    The 1.3.239 layer credits that chain inside one command buffer but not at submit time
    across command buffers: there it wants the transition's src access scope to meet the
    accesses the write was made visible to (the reads), and otherwise reports
    WRITE_AFTER_WRITE for "storage write -> (barrier, no layout change) -> storage read ->
    transition" (random graphs seed 0 and 9, tests/test_run_fuzz.py), and likewise for an
    aliased resource's first transition (from UNDEFINED) after the previous occupant's reads
    (seeds 0 and 32 with 10 passes, aliased). Naming the reads in srcAccessMask records the
    same dependency in the form the layer understands. Applied after fitting the barrier to
    the queue family, so that a src scope left without accesses there gets it too."""
    # from UNDEFINED even with a src access: aliased memory whose previous occupants ended
    # with reads and with writes (seed 0/32 aliased, lavapipe and H100) names the reads too
    if (_is_transition_after_reads(spec) or (spec.old_layout == "UNDEFINED" and spec.src_stages)) \
            and "MEMORY_READ" not in spec.src_access:
        return replace(spec, src_access=tuple(sorted({*spec.src_access, *AFTER_READS_ACCESS})))
    return spec


def _lower_one(b: dict, role: str, families: Mapping[str, int]) -> list[tuple[int, BarrierSpec]]:
    """(call index, struct) pairs for one plan barrier (see ``lower_barriers``)."""
    src, dst = b["src"], b["dst"]
    resource, sub = b["resource"], b.get("subresource")
    crossing = src["queue"] != dst["queue"]
    transfer = crossing and families[src["queue"]] != families[dst["queue"]]
    aspect = dst["layout"] if dst["layout"] not in (None, "UNDEFINED") else src["layout"]
    src_stages, src_access = tuple(src["stages"]), tuple(src["access"])
    dst_stages, dst_access = tuple(dst["stages"]), tuple(dst["access"])
    if not transfer:
        if crossing and role == "release":
            return []  # same family: executed once, at the acquire point
        return [(0, BarrierSpec(resource, sub, src_stages, src_access, dst_stages, dst_access, src["layout"],
                                dst["layout"], None, None, aspect))]
    pair = (families[src["queue"]], families[dst["queue"]])
    held = src["layout"]  # the layout the resource keeps while it changes hands
    if role == "release":
        return [(0, BarrierSpec(resource, sub, src_stages, src_access, (), (), held, held, *pair, aspect))]
    out = [(0, BarrierSpec(resource, sub, dst_stages, (), dst_stages, dst_access, held, held, *pair, aspect))]
    if src["layout"] != dst["layout"]:
        out.append((1, BarrierSpec(resource, sub, dst_stages, (), dst_stages, dst_access, src["layout"], dst["layout"],
                                   None, None, aspect)))
    return out


@dataclass
class BarrierBatch:
    """One vkCmdPipelineBarrier2's structs, kept alive until recorded."""

    dependency: Any
    keep: list[Any] = field(default_factory=list)
    count: int = 0


def build_barriers(device: Device, resources: ResourceSet, set_index: int, barriers: list[dict],
                   role: str, queue: str, wait_stages: Sequence[str] = (),
                   writers: Mapping[int, tuple[str, ...]] | None = None,
                   partial_handoffs: Set[int] = frozenset()) -> list[BarrierBatch]:
    """Sync2 structs for plan barriers recorded on plan queue ``queue`` (see ``lower_barriers``):
    one batch per vkCmdPipelineBarrier2, to be recorded in order; [] when there is nothing."""
    return [_dependency(resources, set_index, group)
            for group in lower_barriers(barriers, role, device.families, wait_stages,
                                        device.capabilities.get(queue, CAPABILITIES), writers, partial_handoffs)]


def _family(index: int | None) -> int:
    return vk().VK_QUEUE_FAMILY_IGNORED if index is None else index


def _dependency(resources: ResourceSet, set_index: int, specs: list[BarrierSpec]) -> BarrierBatch:
    v = vk()
    images, buffers, memory = [], [], []
    for b in specs:
        masks = {"srcStageMask": names.stages(b.src_stages), "srcAccessMask": names.accesses(b.src_access),
                 "dstStageMask": names.stages(b.dst_stages), "dstAccessMask": names.accesses(b.dst_access)}
        if b.resource is None:
            memory.append(v.VkMemoryBarrier2(**masks))
            continue
        r = resources.get(b.resource, set_index)
        masks |= {"srcQueueFamilyIndex": _family(b.src_family), "dstQueueFamilyIndex": _family(b.dst_family)}
        if r.is_image:
            sub = b.subresource
            rng = v.VkImageSubresourceRange(
                aspectMask=_aspect_for_layout(r.plan["format"], b.aspect_layout),
                baseMipLevel=sub["mips"][0], levelCount=sub["mips"][1] - sub["mips"][0],
                baseArrayLayer=sub["layers"][0], layerCount=sub["layers"][1] - sub["layers"][0])
            images.append(v.VkImageMemoryBarrier2(
                oldLayout=names.layout(b.old_layout), newLayout=names.layout(b.new_layout), image=r.handle,
                subresourceRange=rng, **masks))
        else:
            buffers.append(v.VkBufferMemoryBarrier2(buffer=r.handle, offset=0, size=names.WHOLE_SIZE, **masks))
    dep = v.VkDependencyInfo(
        memoryBarrierCount=len(memory), pMemoryBarriers=memory or None,
        imageMemoryBarrierCount=len(images), pImageMemoryBarriers=images or None,
        bufferMemoryBarrierCount=len(buffers), pBufferMemoryBarriers=buffers or None)
    return BarrierBatch(dep, [images, buffers, memory], len(images) + len(buffers) + len(memory))


class RecordContext(RayTracingCommands):
    """Commands a pass implementation may record. Deliberately no barriers."""

    def __init__(self, device: Device, command_buffer: Any) -> None:
        self._device = device
        self._cb = command_buffer

    # pipeline state
    def bind_compute(self, pipeline: Any, layout: Any, descriptor_sets: list[Any]) -> None:
        v = vk()
        v.vkCmdBindPipeline(self._cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, pipeline)
        if descriptor_sets:
            v.vkCmdBindDescriptorSets(self._cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0,
                                      len(descriptor_sets), descriptor_sets, 0, None)

    def bind_graphics(self, pipeline: Any, layout: Any, descriptor_sets: list[Any]) -> None:
        v = vk()
        v.vkCmdBindPipeline(self._cb, v.VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline)
        if descriptor_sets:
            v.vkCmdBindDescriptorSets(self._cb, v.VK_PIPELINE_BIND_POINT_GRAPHICS, layout, 0,
                                      len(descriptor_sets), descriptor_sets, 0, None)

    def bind(self, pipeline: Any, descriptor_sets: Sequence[Any] = (), first_set: int = 0) -> None:
        """Bind a ``rgraph.vk.passkit.Pipeline`` and descriptor sets from ``first_set``."""
        v = vk()
        v.vkCmdBindPipeline(self._cb, pipeline.bind_point, pipeline.pipeline)
        if descriptor_sets and pipeline.bind_point == v.VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR:
            from rgraph.vk.rt_device import bind_descriptor_sets
            from rgraph.vk.rt_pipeline import all_rt_stages

            bind_descriptor_sets(self._device, self._cb, pipeline.layout, all_rt_stages(), list(descriptor_sets),
                                 first_set)
        elif descriptor_sets:
            v.vkCmdBindDescriptorSets(self._cb, pipeline.bind_point, pipeline.layout, first_set,
                                      len(descriptor_sets), list(descriptor_sets), 0, None)

    def push(self, pipeline: Any, data: bytes, offset: int = 0) -> None:
        """Push constants to a ``Pipeline`` (all of its push stages)."""
        self.push_constants(pipeline.layout, pipeline.push_stages, data, offset)

    def push_constants(self, layout: Any, stages: int, data: bytes, offset: int = 0) -> None:
        v = vk()
        buf = v.ffi.new("char[]", data)
        v.vkCmdPushConstants(self._cb, layout, stages, offset, len(data), buf)

    def bind_vertex_buffers(self, buffers: list[Any], offsets: list[int] | None = None) -> None:
        if buffers:
            vk().vkCmdBindVertexBuffers(self._cb, 0, len(buffers), buffers, offsets or [0] * len(buffers))

    def bind_index_buffer(self, buffer: Any, offset: int = 0) -> None:
        v = vk()
        v.vkCmdBindIndexBuffer(self._cb, buffer, offset, v.VK_INDEX_TYPE_UINT32)

    # render pass scope (attachments' layouts are the plan's; no implicit transitions)
    def begin_render_pass(self, render_pass: Any, framebuffer: Any, extent: tuple[int, int],
                          clear_values: list[Any]) -> None:
        v = vk()
        info = v.VkRenderPassBeginInfo(
            renderPass=render_pass, framebuffer=framebuffer,
            renderArea=v.VkRect2D(offset=v.VkOffset2D(x=0, y=0), extent=v.VkExtent2D(width=extent[0], height=extent[1])),
            clearValueCount=len(clear_values), pClearValues=clear_values or None)
        v.vkCmdBeginRenderPass(self._cb, info, v.VK_SUBPASS_CONTENTS_INLINE)

    def end_render_pass(self) -> None:
        vk().vkCmdEndRenderPass(self._cb)

    # work
    def draw(self, vertices: int, instances: int = 1, first_vertex: int = 0, first_instance: int = 0) -> None:
        vk().vkCmdDraw(self._cb, vertices, instances, first_vertex, first_instance)

    def draw_indexed(self, indices: int, instances: int = 1, first_index: int = 0, vertex_offset: int = 0,
                     first_instance: int = 0) -> None:
        vk().vkCmdDrawIndexed(self._cb, indices, instances, first_index, vertex_offset, first_instance)

    def draw_indirect(self, buffer: Any, offset: int) -> None:
        vk().vkCmdDrawIndirect(self._cb, buffer, offset, 1, 16)

    def draw_indexed_indirect(self, buffer: Any, offset: int) -> None:
        vk().vkCmdDrawIndexedIndirect(self._cb, buffer, offset, 1, 20)

    def dispatch(self, x: int, y: int, z: int = 1) -> None:
        vk().vkCmdDispatch(self._cb, x, y, z)

    def dispatch_indirect(self, buffer: Any, offset: int) -> None:
        vk().vkCmdDispatchIndirect(self._cb, buffer, offset)

    def copy_buffer(self, src: Any, dst: Any, regions: list[Any]) -> None:
        vk().vkCmdCopyBuffer(self._cb, src, dst, len(regions), regions)

    def copy_image(self, src: Any, src_layout: int, dst: Any, dst_layout: int, regions: list[Any]) -> None:
        vk().vkCmdCopyImage(self._cb, src, src_layout, dst, dst_layout, len(regions), regions)

    def copy_buffer_to_image(self, src: Any, dst: Any, dst_layout: int, regions: list[Any]) -> None:
        vk().vkCmdCopyBufferToImage(self._cb, src, dst, dst_layout, len(regions), regions)

    def copy_image_to_buffer(self, src: Any, src_layout: int, dst: Any, regions: list[Any]) -> None:
        vk().vkCmdCopyImageToBuffer(self._cb, src, src_layout, dst, len(regions), regions)
