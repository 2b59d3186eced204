"""Execute a plan on a Vulkan device: resources, recorded command buffers, submits, readback.

Command buffers are recorded once per frame-in-flight set (2) and resubmitted; per frame
only the timeline values in the prebuilt submit structs change. Passes are grouped into
batches: contiguous runs (in plan order) on one VkQueue, cut before a pass with waits and
after a pass with signals; one command buffer and one VkSubmitInfo2 per batch, submitted in
plan order. Frames are paced by fences (the validation layer understands fence waits).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rgraph.probe.semantics import mip_extent, subresources
from rgraph.probe.simulate import simulate
from rgraph.probe.values import codec, initial_value, modulus
from rgraph.stages import CAPABILITIES, fit_to_queue
from rgraph.vk import names
from rgraph.vk.accel import AccelSet
from rgraph.vk.after_reads import src_additions
from rgraph.vk.device import Device, create_device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.impl_pass import ImplPass
from rgraph.vk.instance import Instance, ValidationMessage, create_instance
from rgraph.vk.layer_races import avoid_layer_races, touched_resources
from rgraph.vk.loader import vk
from rgraph.vk.packed_ranges import partial_handoffs
from rgraph.vk.probe import ProbePass, fill_bytes, image_copy_regions
from rgraph.vk.probe_rt import needs_ray_tracing, probe_pass, refuse_layer_for_ray_tracing
from rgraph.vk.readback import Mismatch, compare_buffer, compare_image, image_to_rgba8, write_png
from rgraph.vk.record import BarrierBatch, RecordContext, build_barriers
from rgraph.vk.resources import HostBuffer, ResourceSet
from rgraph.vk.semaphore_edges import BatchSync, batch_semaphores, semaphore_count
from rgraph.vk.texels import decode, encode

FRAMES_IN_FLIGHT = 2
#: Vulkan calls bracketed in ``Executor.run_frames`` marks before the submits, in order.
FRAME_CALLS = ("vkWaitForFences", "vkGetQueryPoolResults", "vkResetFences", "vkResetQueryPool")


def marks_per_frame(submit_calls: int) -> int:
    """Marks ``Executor.run_frames`` takes per frame: the start, then a pair per Vulkan call."""
    return 1 + 2 * (len(FRAME_CALLS) + submit_calls)


@dataclass
class RunResult:
    messages: list[ValidationMessage]
    timings: dict[str, Any]  # {"passes": {name: median ms}, "total_ms": median, "frames": n, "cpu_frame_ms": ...}
    data_ok: bool | None  # None: not checked
    device_name: str
    mismatches: list[Mismatch] = field(default_factory=list)
    unchecked: list[str] = field(default_factory=list)  # outputs the data check could not predict
    # read-back outputs as shader-visible values: images (h, w, c) float32 (layers > 1: (layers, h, w, c),
    # mip 0), buffers uint8; present when asked for (read_outputs) or when checking data
    outputs: dict[str, Any] = field(default_factory=dict)
    # pass name -> the params its implementation looked up (rgraph.vk.passkit.PassParams)
    params_read: dict[str, list[str]] = field(default_factory=dict)


@dataclass
class Batch:
    queue: str  # plan queue of the first pass (all passes share its VkQueue)
    passes: list[dict]
    command_buffers: list[Any] = field(default_factory=list)  # per set


@dataclass
class SubmitCall:
    """One vkQueueSubmit2 of a frame: ``count`` prebuilt VkSubmitInfo2 in ``infos``."""

    queue: Any
    count: int
    infos: Any
    fence: Any  # VkFence or ffi.NULL
    context: str  # for validation messages
    keep: list[Any]  # cffi arrays the infos point into


def make_batches(plan: dict, device: Device, one_per_pass: bool = False) -> list[Batch]:
    """Batches of passes; ``one_per_pass`` (under validation) gives each pass its own named
    command buffer so that validation messages name the pass."""
    batches: list[Batch] = []
    for p in plan["passes"]:
        last = batches[-1] if batches else None
        if (one_per_pass or last is None or not device.same_queue(last.queue, p["queue"]) or p["waits"]
                or last.passes[-1]["signals"]):
            batches.append(Batch(p["queue"], [p]))
        else:
            last.passes.append(p)
    return batches


class Executor:
    """Owns every Vulkan object of one run; ``close`` destroys them in reverse order."""

    def __init__(self, plan: dict, *, validate: bool, device_index: int | None, verbose: bool = True,
                 inputs: dict[str, Any] | None = None, one_call_per_queue: bool = True) -> None:
        if plan.get("format") != "rgraph-plan/1":
            raise ExecutionError("not an rgraph plan (format != rgraph-plan/1)")
        self.plan = plan
        self.verbose = verbose
        self.one_call_per_queue = one_call_per_queue
        self.inputs = dict(inputs or {})
        self.scene_gpu: Any = None
        self.samplers: dict[str, Any] = {}
        self.updaters: list[ImplPass] = []
        if validate:
            refuse_layer_for_ray_tracing(plan)
        self.instance: Instance = create_instance(validate)
        self.device: Device | None = None
        self.resources: ResourceSet | None = None
        self.accels: AccelSet | None = None
        self.passes: list[ProbePass | ImplPass] = []
        self.pools: dict[tuple[int, int], Any] = {}
        self.query_pools: list[Any] = []
        self.fences: list[list[Any]] = []
        self.fence_arrays: list[Any] = []
        self.submit_calls: list[list[SubmitCall]] = []
        self.value_slots: list[list[tuple[Any, int]]] = []
        self.layer_edges = 0  # semaphore edges added only to avoid the 1.3.239 layer's racing false positive
        self.sampler = None
        self.host_buffers: list[HostBuffer] = []
        self.batches: list[Batch] = []
        self.barrier_batches: list[BarrierBatch] = []
        try:
            self.device = create_device(self.instance, device_index, verbose=verbose,
                                        ray_tracing=needs_ray_tracing(plan),
                                        rt_pipelines=any(p["kind"] == "raytrace" for p in plan["passes"]))
            self._setup()
        except BaseException:
            self.close()
            raise

    @property
    def log(self):
        return self.instance.log

    # ----------------------------------------------------------------- setup
    def _setup(self) -> None:
        v = vk()
        dev = self.device
        for p in self.plan["passes"]:
            if p.get("device", 0) != 0:
                raise ExecutionError(f"pass {p['name']!r}: multi-device plans are not supported")
        self.log.context = "creating resources"
        self.resources = ResourceSet(dev, self.plan, FRAMES_IN_FLIGHT)
        self.sampler = v.vkCreateSampler(dev.handle, v.VkSamplerCreateInfo(
            magFilter=v.VK_FILTER_NEAREST, minFilter=v.VK_FILTER_NEAREST,
            mipmapMode=v.VK_SAMPLER_MIPMAP_MODE_NEAREST, addressModeU=v.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
            addressModeV=v.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, addressModeW=v.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
            maxLod=1000.0), None)
        self.log.context = "initialising persistent resources"
        self._init_shared()
        if any(r["kind"] == "accel" for r in self.plan["resources"]):
            self.log.context = "building persistent acceleration structures"
            self.accels = AccelSet(dev, self.plan, self.resources, self._one_time)
        self._release_for_first_frame()
        self.log.context = "creating pipelines"
        for p in self.plan["passes"]:
            self.log.context = f"creating pipelines of pass {p['name']}"
            if p.get("impl"):
                self.passes.append(ImplPass(dev, self.plan, p, self.resources, sets=FRAMES_IN_FLIGHT,
                                            scene=self._scene, samplers=self.samplers))
                self.passes[-1].setup.accels = self.accels  # rgraph.vk.accel.AccelSet (impl accel_build)
            else:
                self.passes.append(probe_pass(dev, self.plan, p, self.resources, self.sampler, self.accels))
        self.updaters = [p for p in self.passes if isinstance(p, ImplPass) and _overrides_update(p)]
        n = len(self.plan["passes"])
        for _ in range(FRAMES_IN_FLIGHT):
            self.query_pools.append(v.vkCreateQueryPool(dev.handle, v.VkQueryPoolCreateInfo(
                queryType=v.VK_QUERY_TYPE_TIMESTAMP, queryCount=max(2 * n, 2)), None))
            # reset from the host (hostQueryReset): vkCmdResetQueryPool is not allowed on a
            # transfer-only queue family, and one host call per frame replaces one per pass
            v.vkResetQueryPool(dev.handle, self.query_pools[-1], 0, max(2 * n, 2))
        self.batches = make_batches(self.plan, dev, one_per_pass=self.instance.validate)
        self.log.context = "recording"
        self._record()

    def _scene(self) -> Any:
        """The scene's geometry on the device (``rgraph.vk.scene_gpu``), built on first use."""
        if self.scene_gpu is None:
            from rgraph.vk.scene_gpu import SceneGPU

            context = self.log.context
            self.log.context = "uploading the scene"
            self.scene_gpu = SceneGPU(self.device, self.plan, FRAMES_IN_FLIGHT, self._one_time)
            self.log.context = context
        return self.scene_gpu

    def _pool(self, family: int, set_index: int) -> Any:
        v = vk()
        key = (family, set_index)
        if key not in self.pools:
            self.pools[key] = v.vkCreateCommandPool(self.device.handle, v.VkCommandPoolCreateInfo(
                queueFamilyIndex=family), None)
        return self.pools[key]

    def _one_time(self, queue: str, record) -> None:
        """Record, submit and wait for a one-time command buffer on plan queue ``queue``."""
        v = vk()
        dev = self.device
        pool = self._pool(dev.families[queue], FRAMES_IN_FLIGHT)  # a separate pool for one-time work
        cb = v.vkAllocateCommandBuffers(dev.handle, v.VkCommandBufferAllocateInfo(
            commandPool=pool, level=v.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1))[0]
        v.vkBeginCommandBuffer(cb, v.VkCommandBufferBeginInfo(flags=v.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))
        record(cb)
        v.vkEndCommandBuffer(cb)
        fence = v.vkCreateFence(dev.handle, v.VkFenceCreateInfo(), None)
        cb_info = v.VkCommandBufferSubmitInfo(commandBuffer=cb)
        submit = v.VkSubmitInfo2(commandBufferInfoCount=1, pCommandBufferInfos=[cb_info])
        v.vkQueueSubmit2(dev.queues[queue], 1, [submit], fence)
        v.vkWaitForFences(dev.handle, 1, [fence], v.VK_TRUE, 10**11)
        v.vkDestroyFence(dev.handle, fence, None)
        v.vkFreeCommandBuffers(dev.handle, pool, 1, [cb])

    def _init_shared(self) -> None:
        """Fill persistent/imported resources with their initial value, then move them to ``final``."""
        v = vk()
        plan_size = tuple(self.plan.get("size") or (64, 64))
        by_queue: dict[str, list] = {}
        handoffs: dict[str, list] = {}  # final queue -> images initialised on graphics
        for r in self.resources.shared():
            if r.plan["kind"] == "accel":  # built by rgraph.vk.accel.AccelSet
                continue
            queue = r.plan["final"]["queue"]
            if _needs_graphics_copy(r, self.device, queue):
                handoffs.setdefault(queue, []).append(r)
                queue = "graphics"
            by_queue.setdefault(queue, []).append(r)
        for queue, items in by_queue.items():
            work = []
            for r in items:
                res = r.plan
                m = modulus(res)
                value = initial_value(res["name"], m) if m else None
                if r.is_image:
                    whole = {"subresource": {"mips": [0, res["mips"]], "layers": [0, res["layers"]]}}
                    data = fill_bytes(res, value, subresources(whole), plan_size)
                    regions = image_copy_regions(res, whole)[0]
                else:
                    data = fill_bytes(res, value, [None], plan_size)
                    regions = None
                if res["name"] in self.inputs:
                    data = _input_bytes(res, self.inputs[res["name"]], len(data))
                buf = HostBuffer.create(self.device, len(data), v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
                buf.write(data)
                self.host_buffers.append(buf)
                work.append((r, buf, regions))

            def record(cb, work=work, queue=queue):
                keep = []
                for r, buf, regions in work:
                    final = r.plan["final"]
                    if r.is_image:
                        rng = _whole_range(r)
                        keep.append(_image_barrier(cb, r, rng, (0, 0), _copy_write(), v.VK_IMAGE_LAYOUT_UNDEFINED,
                                                   v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL))
                        v.vkCmdCopyBufferToImage(cb, buf.handle, r.handle, v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                                 len(regions), regions)
                        if final["queue"] != queue:  # release to the final queue's family
                            keep.append(_ownership_barrier(cb, r, rng, self.device, "graphics", final["queue"], True))
                        else:
                            keep.append(_image_barrier(cb, r, rng, _copy_write(), _any_access(),
                                                       v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                                       names.layout(final["layout"])))
                    else:
                        size = int(r.plan["size_bytes"] or r.plan["bytes"])
                        v.vkCmdCopyBuffer(cb, buf.handle, r.handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0,
                                                                                      size=size)])
                        keep.append(_buffer_barrier(cb, r, _copy_write(), _any_access()))

            self._one_time(queue, record)
        for queue, items in handoffs.items():
            self._one_time(queue, lambda cb, items=items, queue=queue: _acquire_initialised(cb, items, self.device, queue))

    def _release_for_first_frame(self) -> None:
        """Ownership releases that frame 0's acquires pair with.

        A persistent resource whose last use in a frame is on another queue family than its
        first use is released at that last use and acquired at the next frame's first use.
        Frame 0 has no previous frame, so after initialisation (which leaves the resource in
        its ``final`` state on its final queue) the runtime records those same releases once."""
        shared = {r.plan["name"] for r in self.resources.shared()}
        for queue, releases in first_frame_releases(self.plan, shared).items():
            batches = build_barriers(self.device, self.resources, 0, releases, "release", queue)
            if batches:
                self.log.context = f"releasing persistent resources for frame 0 on {queue}"
                self._one_time(queue, lambda cb, batches=batches: _record_barriers(cb, batches))

    def _label(self, cb: Any, text: str | None) -> None:
        v = vk()
        if text is None:
            fn = self.device.fn("vkCmdEndDebugUtilsLabelEXT")
            if fn:
                fn(cb)
            return
        fn = self.device.fn("vkCmdBeginDebugUtilsLabelEXT")
        if fn:
            label = v.VkDebugUtilsLabelEXT(pLabelName=text, color=[0.0, 0.0, 0.0, 0.0])
            fn(cb, label)

    def _name_object(self, handle: Any, object_type: int, name: str) -> None:
        v = vk()
        fn = self.device.fn("vkSetDebugUtilsObjectNameEXT")
        if not fn:
            return
        raw = int(v.ffi.cast("uint64_t", handle))
        fn(self.device.handle, v.VkDebugUtilsObjectNameInfoEXT(objectType=object_type, objectHandle=raw,
                                                               pObjectName=name))

    def _record(self) -> None:
        v = vk()
        dev = self.device
        index_of = {id(p): i for i, p in enumerate(self.plan["passes"])}
        queue_ids = _queue_ids(dev)
        writers = src_additions(self.plan, queue_ids.__getitem__)
        handoffs = partial_handoffs(self.plan)
        for s in range(FRAMES_IN_FLIGHT):
            for bi, batch in enumerate(self.batches):
                pool = self._pool(dev.families[batch.queue], s)
                cb = v.vkAllocateCommandBuffers(dev.handle, v.VkCommandBufferAllocateInfo(
                    commandPool=pool, level=v.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1))[0]
                label = (f"pass {batch.passes[0]['name']} (set {s})" if len(batch.passes) == 1
                         else f"batch {bi} (set {s}): " + ",".join(p["name"] for p in batch.passes))
                self._name_object(cb, v.VK_OBJECT_TYPE_COMMAND_BUFFER, label)
                batch.command_buffers.append(cb)
                v.vkBeginCommandBuffer(cb, v.VkCommandBufferBeginInfo())
                ctx = RecordContext(dev, cb)
                timestamps = dev.timestamp_valid_bits.get(batch.queue, 0) > 0
                for p in batch.passes:
                    i = index_of[id(p)]
                    self.log.context = f"recording pass {p['name']}"
                    self._label(cb, f"pass {p['name']}")
                    if timestamps:
                        v.vkCmdWriteTimestamp2(cb, v.VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, self.query_pools[s], 2 * i)
                    waited = [st for w in p["waits"] if not dev.same_queue(w["queue"], p["queue"]) for st in w["stages"]]
                    for barriers in build_barriers(dev, self.resources, s, p["barriers"], "barrier", p["queue"], waited,
                                                   writers[i], handoffs[i]):
                        self.barrier_batches.append(barriers)
                        v.vkCmdPipelineBarrier2(cb, barriers.dependency)
                    self.passes[i].record(ctx, s)
                    for releases in build_barriers(dev, self.resources, s, p["releases"], "release", p["queue"]):
                        self.barrier_batches.append(releases)
                        v.vkCmdPipelineBarrier2(cb, releases.dependency)
                    if timestamps:
                        v.vkCmdWriteTimestamp2(cb, v.VK_PIPELINE_STAGE_2_BOTTOM_OF_PIPE_BIT, self.query_pools[s],
                                               2 * i + 1)
                    self._label(cb, None)
                v.vkEndCommandBuffer(cb)
        self._build_submits()

    def _build_submits(self) -> None:
        """Prebuilt submit arrays per set; per frame only the semaphore values change.

        Each batch is one VkSubmitInfo2 (its semaphores order it against the other queues).
        Batches go in ``submission_order`` (each VkQueue runs ahead as far as its waits allow;
        every wait is submitted after its signal). Under validation each batch is its own
        vkQueueSubmit2 call so that messages name the batch. Without validation each VkQueue
        gets one call per frame with all its batches (``one_call_per_queue``, the default: a
        wait may then be submitted before its signal, which timeline semaphores allow, and the
        driver's per-call cost is paid once per queue), or, with it off, one call per run of
        consecutive batches on one VkQueue in submission order.
        Semaphores: one per edge (rgraph.vk.semaphore_edges), value = frame + offset, written
        straight into the cffi structs; edges the 1.3.239 layer's racing check needs to see a
        sync are added where its model predicts a false report (rgraph.vk.layer_races).
        """
        v = vk()
        ffi = v.ffi
        dev = self.device
        handle_of = _queue_ids(dev)
        syncs = [BatchSync(b.queue, handle_of[b.queue],
                           tuple((w["queue"], w["value"], names.stages(w["stages"])) for w in b.passes[0]["waits"]),
                           tuple((sg["queue"], sg["value"], names.stages(sg["stages"])) for sg in b.passes[-1]["signals"]),
                           touched_resources(b.passes))
                 for b in self.batches]
        try:
            edges, order, self.layer_edges = avoid_layer_races(syncs, v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT)
        except ValueError as exc:
            raise ExecutionError(f"plan semaphores: {exc}") from None
        semaphores = [dev.new_timeline() for _ in range(semaphore_count(edges, FRAMES_IN_FLIGHT))]
        last_of: dict[int, int] = {}
        for bi, batch in enumerate(self.batches):
            last_of[handle_of[batch.queue]] = bi
        fence_batches = sorted(set(last_of.values()))
        # calls: runs of consecutive batches on one VkQueue (one batch each under validation)
        runs: list[list[int]] = []
        if self.instance.validate:
            runs = [[bi] for bi in order]
        elif self.one_call_per_queue:  # waits may come before their signals: timeline semantics allow it
            per_queue: dict[int, list[int]] = {}
            for bi in order:
                per_queue.setdefault(handle_of[self.batches[bi].queue], []).append(bi)
            runs = list(per_queue.values())
        else:
            for bi in order:
                batch = self.batches[bi]
                if runs and handle_of[self.batches[runs[-1][-1]].queue] == handle_of[batch.queue]:
                    runs[-1].append(bi)
                else:
                    runs.append([bi])
        self.fences = [[v.vkCreateFence(dev.handle, v.VkFenceCreateInfo(flags=v.VK_FENCE_CREATE_SIGNALED_BIT), None)
                        for _ in fence_batches] for _ in range(FRAMES_IN_FLIGHT)]
        self.fence_arrays = [ffi.new("VkFence[]", fences) if fences else ffi.NULL for fences in self.fences]
        self.submit_calls = []
        self.value_slots = []
        for s in range(FRAMES_IN_FLIGHT):
            calls: list[SubmitCall] = []
            slots: list[tuple[Any, int]] = []
            for run in runs:
                infos = ffi.new("VkSubmitInfo2[]", len(run))
                keep: list[Any] = [infos]
                for j, bi in enumerate(run):
                    batch = self.batches[bi]
                    waits, signals = batch_semaphores(edges, FRAMES_IN_FLIGHT, s, bi)
                    info = infos[j]
                    info.sType = v.VK_STRUCTURE_TYPE_SUBMIT_INFO_2
                    for count_field, array_field, specs in (("waitSemaphoreInfoCount", "pWaitSemaphoreInfos", waits),
                                                            ("signalSemaphoreInfoCount", "pSignalSemaphoreInfos",
                                                             signals)):
                        if not specs:
                            continue
                        array = ffi.new("VkSemaphoreSubmitInfo[]", len(specs))
                        keep.append(array)
                        for k, use in enumerate(specs):
                            array[k].sType = v.VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO
                            array[k].semaphore = semaphores[use.semaphore]
                            array[k].stageMask = use.stages
                            slots.append((array[k], use.offset))
                        setattr(info, count_field, len(specs))
                        setattr(info, array_field, array)
                    cbi = ffi.new("VkCommandBufferSubmitInfo[]", 1)
                    cbi[0].sType = v.VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO
                    cbi[0].commandBuffer = batch.command_buffers[s]
                    keep.append(cbi)
                    info.commandBufferInfoCount = 1
                    info.pCommandBufferInfos = cbi
                fence_index = next((fence_batches.index(bi) for bi in run if bi in fence_batches), None)
                fence = self.fences[s][fence_index] if fence_index is not None else ffi.NULL
                context = "submit of " + ", ".join(f"batch {bi} [{', '.join(p['name'] for p in self.batches[bi].passes)}]"
                                                   for bi in run)
                calls.append(SubmitCall(dev.queues[self.batches[run[0]].queue], len(run), infos, fence, context, keep))
            self.submit_calls.append(calls)
            self.value_slots.append(slots)

    # ----------------------------------------------------------------- frames
    def run_frames(self, frames: int, marks: list[float] | None = None) -> dict[str, Any]:
        """Submit ``frames`` frames; per-pass GPU medians from timestamps.

        ``marks`` (if given) gets time.perf_counter() readings, ``marks_per_frame(calls)`` per
        frame (calls in ``FRAME_CALLS`` order): the frame's start, then a (before, after) pair around each
        Vulkan call - the fence wait (time blocked on the GPU), the timestamp read, the fence
        reset, the query reset, each vkQueueSubmit2 - with the per-frame updates (scene and
        pass ``update`` hooks) and semaphore values between them. A call a frame skips (no
        timestamps yet) still gets its pair, an empty interval. benchmarks/frame_cpu.py splits
        a frame into blocked, Vulkan calls and Python from them.

        The loop calls the binding's raw cffi functions with prebuilt arrays: per frame one fence
        wait and reset, one query read into a preallocated buffer (copied into a numpy row), the
        timeline values, and one vkQueueSubmit2 per call of ``submit_calls``.
        """
        import numpy as np

        v = vk()
        lib, ffi = v.lib, v.ffi
        dev = self.device
        log = self.log
        validate = self.instance.validate
        n = len(self.plan["passes"])
        handle = dev.handle
        fence_counts = [len(f) for f in self.fences]
        fence_arrays = self.fence_arrays
        pools = self.query_pools
        timestamps = n > 0 and all(dev.timestamp_valid_bits.get(p["queue"], 0) > 0 for p in self.plan["passes"])
        query_buffer = ffi.new("uint64_t[]", max(2 * n, 1))
        query_view = np.frombuffer(ffi.buffer(query_buffer), dtype=np.uint64)
        rows = np.zeros((frames, 2 * n), dtype=np.uint64)
        collected = 0
        query_flags = v.VK_QUERY_RESULT_64_BIT
        cpu_s = np.zeros(frames)
        submitted = [False] * FRAMES_IN_FLIGHT
        scene, updaters = self.scene_gpu, self.updaters
        wait_fences, reset_fences, submit2 = lib.vkWaitForFences, lib.vkResetFences, lib.vkQueueSubmit2
        get_queries, reset_queries = lib.vkGetQueryPoolResults, lib.vkResetQueryPool
        timeout = 10**11
        perf = time.perf_counter
        timed = marks is not None
        mark = marks.append if marks is not None else None
        for frame in range(frames):
            s = frame % FRAMES_IN_FLIGHT
            t0 = perf()
            if timed:
                mark(t0)
            log.context = f"frame {frame}"  # also a hook: tests/test_soak.py samples RSS on it
            fenced = fence_counts[s] > 0
            if timed:
                mark(perf())
            if fenced:
                _check(wait_fences(handle, fence_counts[s], fence_arrays[s], 1, timeout), "vkWaitForFences")
            if timed:
                mark(perf())
                mark(perf())
            if fenced and submitted[s] and timestamps:
                read = get_queries(handle, pools[s], 0, 2 * n, 16 * n, query_buffer, 8, query_flags) == 0
                if timed:
                    mark(perf())
                if read:
                    rows[collected] = query_view
                    collected += 1
            elif timed:
                mark(perf())
            if timed:
                mark(perf())
            if fenced:
                _check(reset_fences(handle, fence_counts[s], fence_arrays[s]), "vkResetFences")
            if timed:
                mark(perf())
                mark(perf())
            if fenced and timestamps:
                reset_queries(handle, pools[s], 0, 2 * n)
            if timed:
                mark(perf())
            if scene is not None:
                scene.update(frame, s)
            for p in updaters:
                p.update(frame, s)
            for slot, offset in self.value_slots[s]:
                slot.value = frame + offset
            for call in self.submit_calls[s]:
                if validate:
                    log.context = f"frame {frame} {call.context}"
                if timed:
                    mark(perf())
                _check(submit2(call.queue, call.count, call.infos, call.fence), "vkQueueSubmit2")
                if timed:
                    mark(perf())
            submitted[s] = True
            cpu_s[frame] = perf() - t0
        log.context = "finishing"
        for s in range(FRAMES_IN_FLIGHT):
            if submitted[s] and fence_counts[s]:
                _check(wait_fences(handle, fence_counts[s], fence_arrays[s], 1, timeout), "vkWaitForFences")
                if timestamps and get_queries(handle, pools[s], 0, 2 * n, 16 * n, query_buffer, 8, query_flags) == 0:
                    rows[collected] = query_view
                    collected += 1
        return self._timings(rows[:collected], frames, cpu_s)

    def _timings(self, rows: Any, frames: int, cpu_s: Any) -> dict[str, Any]:
        """Medians (ms) from timestamp rows (per frame: start, end of each pass)."""
        import numpy as np

        period = self.device.timestamp_period_ns / 1e6
        per_pass: dict[str, float | None] = {p["name"]: None for p in self.plan["passes"]}
        total = None
        if len(rows):
            stamps = rows.astype(np.float64)
            starts, ends = stamps[:, 0::2], stamps[:, 1::2]
            for i, p in enumerate(self.plan["passes"]):
                per_pass[p["name"]] = float(np.median(ends[:, i] - starts[:, i])) * period
            total = float(np.median(ends.max(axis=1) - starts.min(axis=1))) * period
        from rgraph.vk.pass_intervals import pass_intervals

        return {"passes": per_pass, "total_ms": total, "frames": frames,
                "cpu_submit_ms": float(np.median(cpu_s)) * 1000.0 if frames else None,
                "intervals": pass_intervals(self.plan, rows, period)}

    # ----------------------------------------------------------------- readback
    def read_back(self, frames: int) -> dict[tuple, bytes]:
        """Bytes of every output/persistent/imported subresource after the last frame."""
        v = vk()
        s = (frames - 1) % FRAMES_IN_FLIGHT
        out: dict[tuple, bytes] = {}
        wanted = [r for r in self.plan["resources"] if r["lifetime"] in ("output", "persistent", "imported")
                  and r.get("first") is not None and r["kind"] != "accel"]  # accels: checked through traces
        by_queue: dict[str, list[dict]] = {}
        for res in wanted:
            by_queue.setdefault(res["final"]["queue"], []).append(res)
        for queue, items in by_queue.items():
            jobs = []
            for res in items:
                r = self.resources.get(res["name"], s)
                if r.is_image:
                    whole = {"subresource": {"mips": [0, res["mips"]], "layers": [0, res["layers"]]}}
                    regions, size = image_copy_regions(res, whole)
                else:
                    regions, size = None, int(res["size_bytes"] or res["bytes"])
                buf = HostBuffer.create(self.device, size, v.VK_BUFFER_USAGE_TRANSFER_DST_BIT)
                self.host_buffers.append(buf)
                jobs.append((res, r, buf, regions, size))

            capabilities = self.device.capabilities.get(queue, CAPABILITIES)

            def record(cb, jobs=jobs, capabilities=capabilities):
                keep = []
                for res, r, buf, regions, size in jobs:
                    # the final state may name stages of another family (a graphics read of a
                    # resource whose last queue is compute: INDEX_INPUT, H100 fuzz seed 32/32)
                    stages, access = fit_to_queue(res["final"]["stages"], res["final"]["access"], capabilities)
                    src = names.stages(stages), names.accesses(access)
                    copy_read = v.VK_PIPELINE_STAGE_2_COPY_BIT, v.VK_ACCESS_2_TRANSFER_READ_BIT
                    if r.is_image:
                        keep.append(_image_barrier(cb, r, _whole_range(r), src, copy_read, names.layout(res["final"]["layout"]),
                                                   v.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL))
                        v.vkCmdCopyImageToBuffer(cb, r.handle, v.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buf.handle,
                                                 len(regions), regions)
                    else:
                        keep.append(_buffer_barrier(cb, r, src, copy_read))
                        v.vkCmdCopyBuffer(cb, r.handle, buf.handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0,
                                                                                      size=size)])

            self.log.context = "readback"
            self._one_time(queue, record)
            for res, _r, buf, _regions, size in jobs:
                data = buf.read(size)
                if res["kind"] == "image":
                    offset = 0
                    for mip in range(res["mips"]):
                        w, h = mip_extent(res, mip)
                        from rgraph.vk.probe import texel_bytes

                        n = texel_bytes(res["format"], w, h)
                        for layer in range(res["layers"]):
                            out[(res["name"], mip, layer)] = data[offset:offset + n]
                            offset += n
                else:
                    out[(res["name"], None, None)] = data
        return out

    # ----------------------------------------------------------------- teardown
    def close(self) -> list[ValidationMessage]:
        v = vk()
        dev = self.device
        if dev is not None and dev.handle is not None:
            self.log.context = "teardown"
            v.vkDeviceWaitIdle(dev.handle)
            for fences in self.fences:
                for f in fences:
                    v.vkDestroyFence(dev.handle, f, None)
            self.fences = []
            for pool in self.query_pools:
                v.vkDestroyQueryPool(dev.handle, pool, None)
            self.query_pools = []
            for pool in self.pools.values():
                v.vkDestroyCommandPool(dev.handle, pool, None)
            self.pools = {}
            for p in reversed(self.passes):
                p.destroy()
            self.passes = []
            if self.scene_gpu is not None:
                self.scene_gpu.destroy()
                self.scene_gpu = None
            for sampler in self.samplers.values():
                v.vkDestroySampler(dev.handle, sampler, None)
            self.samplers = {}
            for buf in reversed(self.host_buffers):
                buf.destroy()
            self.host_buffers = []
            if self.sampler is not None:
                v.vkDestroySampler(dev.handle, self.sampler, None)
                self.sampler = None
            if self.accels is not None:
                self.accels.destroy()
                self.accels = None
            if self.resources is not None:
                self.resources.destroy()
                self.resources = None
            dev.destroy()
        if self.instance is not None and self.instance.handle is not None:
            self.instance.destroy()
        return self.instance.log.messages


def first_frame_releases(plan: dict, shared: set[str]) -> dict[str, list[dict]]:
    """Plan releases (by releasing queue) of ``shared`` resources whose acquire comes at or
    before the releasing pass: they hand the resource to the next frame."""
    def key(b: dict) -> tuple:
        return b["resource"], str(b.get("subresource")), b["src"]["queue"], b["dst"]["queue"]

    acquires = {key(b): i for i, p in enumerate(plan["passes"]) for b in p["barriers"]
                if b["src"]["queue"] != b["dst"]["queue"]}
    by_queue: dict[str, list[dict]] = {}
    for i, p in enumerate(plan["passes"]):
        for b in p["releases"]:
            if b["resource"] in shared and acquires.get(key(b), len(plan["passes"])) <= i:
                by_queue.setdefault(b["src"]["queue"], []).append(b)
    return by_queue


def _needs_graphics_copy(r: Any, device: Device, queue: str) -> bool:
    """Depth/stencil images can only be copied to on a graphics-capable queue family
    (VUID-vkCmdCopyBufferToImage-commandBuffer-07739): initialise them there and hand them over."""
    v = vk()
    return (r.is_image and names.aspect_mask(r.plan["format"]) != v.VK_IMAGE_ASPECT_COLOR_BIT
            and not device.same_family(queue, "graphics"))


def _record_barriers(cb: Any, batches: list[BarrierBatch]) -> None:
    for b in batches:
        vk().vkCmdPipelineBarrier2(cb, b.dependency)


def _whole_range(r: Any) -> Any:
    return vk().VkImageSubresourceRange(aspectMask=names.aspect_mask(r.plan["format"]), baseMipLevel=0,
                                        levelCount=r.plan["mips"], baseArrayLayer=0, layerCount=r.plan["layers"])


def _image_barrier(cb: Any, r: Any, rng: Any, src: tuple[int, int], dst: tuple[int, int], old_layout: int,
                   new_layout: int, families: tuple[int, int] | None = None) -> tuple:
    """Record one image barrier (``src``/``dst``: (stage mask, access mask); ``families``: an
    ownership transfer's (src, dst) queue families, else IGNORED); the structs to keep alive."""
    v = vk()
    src_family, dst_family = families or (v.VK_QUEUE_FAMILY_IGNORED, v.VK_QUEUE_FAMILY_IGNORED)
    b = v.VkImageMemoryBarrier2(srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1],
                                oldLayout=old_layout, newLayout=new_layout, srcQueueFamilyIndex=src_family,
                                dstQueueFamilyIndex=dst_family, image=r.handle, subresourceRange=rng)
    dep = v.VkDependencyInfo(imageMemoryBarrierCount=1, pImageMemoryBarriers=[b])
    v.vkCmdPipelineBarrier2(cb, dep)
    return b, dep


def _buffer_barrier(cb: Any, r: Any, src: tuple[int, int], dst: tuple[int, int]) -> tuple:
    """Record one whole-buffer barrier (``src``/``dst``: (stage mask, access mask))."""
    v = vk()
    b = v.VkBufferMemoryBarrier2(srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1],
                                 srcQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED,
                                 dstQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED,
                                 buffer=r.handle, offset=0, size=names.WHOLE_SIZE)
    dep = v.VkDependencyInfo(bufferMemoryBarrierCount=1, pBufferMemoryBarriers=[b])
    v.vkCmdPipelineBarrier2(cb, dep)
    return b, dep


def _copy_write() -> tuple[int, int]:
    v = vk()
    return v.VK_PIPELINE_STAGE_2_COPY_BIT, v.VK_ACCESS_2_TRANSFER_WRITE_BIT


def _any_access() -> tuple[int, int]:
    v = vk()
    return v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, v.VK_ACCESS_2_MEMORY_READ_BIT | v.VK_ACCESS_2_MEMORY_WRITE_BIT


def _ownership_barrier(cb: Any, r: Any, rng: Any, device: Device, src: str, dst: str, release: bool) -> tuple:
    """The release (on ``src``) or acquire (on ``dst``) half of an ownership transfer of an
    initialised image, layout kept at TRANSFER_DST_OPTIMAL; returns the structs to keep alive."""
    layout = vk().VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL
    return _image_barrier(cb, r, rng, _copy_write() if release else (0, 0), (0, 0) if release else _any_access(),
                          layout, layout, (device.families[src], device.families[dst]))


def _acquire_initialised(cb: Any, items: list, device: Device, queue: str) -> list:
    """On ``queue``: acquire images initialised on graphics, then move them to their final layout."""
    v = vk()
    keep: list = []
    for r in items:
        rng = _whole_range(r)
        keep.append(_ownership_barrier(cb, r, rng, device, "graphics", queue, False))
        keep.append(_image_barrier(cb, r, rng, (v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0), _any_access(),
                                   v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, names.layout(r.plan["final"]["layout"])))
    return keep


def _queue_ids(device: Device) -> dict[str, int]:
    """Plan queue -> its VkQueue handle as an int (plan queues sharing a VkQueue share it)."""
    ffi = vk().ffi
    return {q: int(ffi.cast("uintptr_t", vk_queue)) for q, vk_queue in device.queues.items()}


def _check(result: int, call: str) -> None:
    if result != 0:
        raise ExecutionError(f"{call} failed: {names_of_result(result)}")


def names_of_result(result: int) -> str:
    v = vk()
    for name in dir(v):
        if name.startswith("VK_") and not name.startswith("VK_STRUCTURE") and getattr(v, name) == result and (
                name.startswith("VK_ERROR_") or name in ("VK_TIMEOUT", "VK_NOT_READY", "VK_INCOMPLETE")):
            return name
    return f"VkResult {result}"


def _overrides_update(p: ImplPass) -> bool:
    from rgraph.impl import PassImpl

    return type(p.impl).update is not PassImpl.update


def _input_bytes(res: dict, value: Any, expected: int) -> bytes:
    """Bytes for an ``inputs`` entry: raw bytes, or an array of shader-visible values (images:
    (h, w, c) or (layers, h, w, c) for mip 0 only, when the image has one mip)."""
    import numpy as np

    if isinstance(value, (bytes, bytearray)):
        data = bytes(value)
    elif res["kind"] == "image":
        arr = np.asarray(value)
        if res["mips"] != 1:
            raise ExecutionError(f"input {res['name']!r}: arrays fill single-mip images only; give raw bytes")
        layers = arr if arr.ndim == 4 else arr[None]
        data = b"".join(encode(res["format"], layer) for layer in layers)
    else:
        data = np.asarray(value).tobytes()
    if len(data) != expected:
        raise ExecutionError(f"input {res['name']!r}: {len(data)} bytes given, the resource holds {expected}")
    return data


def decode_outputs(plan: dict, data: dict[tuple, bytes]) -> dict[str, Any]:
    """Read-back bytes -> shader-visible arrays per resource (mip 0; all layers)."""
    import numpy as np

    out: dict[str, Any] = {}
    for res in plan["resources"]:
        if res["kind"] == "image" and (res["name"], 0, 0) in data:
            w, h = mip_extent(res, 0)
            try:
                layers = [decode(res["format"], data[(res["name"], 0, layer)], w, h) for layer in range(res["layers"])]
            except ValueError:
                continue
            out[res["name"]] = layers[0] if len(layers) == 1 else np.stack(layers)
        elif (res["name"], None, None) in data:
            out[res["name"]] = np.frombuffer(data[(res["name"], None, None)], dtype=np.uint8)
    return out


def execute_plan(plan: dict, *, validate: bool = False, frames: int = 1, device_index: int | None = None,
                 check_data: bool | None = None, out_png: Path | None = None, verbose: bool = False,
                 inputs: dict[str, Any] | None = None, read_outputs: bool = False) -> RunResult:
    """Run ``plan`` for ``frames`` frames; check the probe's data flow (default: when validating).

    ``inputs`` fills imported/persistent resources before the first frame (raw bytes or arrays
    of shader-visible values); ``read_outputs`` returns every output, persistent and imported
    resource decoded in ``RunResult.outputs``. Plans with implemented passes (``impl``) have no
    probe prediction: their data check is left to each pass's NumPy reference.
    """
    if frames < 1:
        raise ExecutionError("--frames must be at least 1")
    check = validate if check_data is None else check_data
    implemented = [p["name"] for p in plan["passes"] if p.get("impl")]
    executor = Executor(plan, validate=validate, device_index=device_index, verbose=verbose, inputs=inputs)
    timings: dict[str, Any] = {}
    mismatches: list[Mismatch] = []
    unchecked: list[str] = []
    outputs: dict[str, Any] = {}
    data_ok: bool | None = None
    try:
        timings = executor.run_frames(frames)
        if check or read_outputs or out_png is not None:
            data = executor.read_back(frames)
            outputs = decode_outputs(plan, data)
            if check and implemented:
                unchecked = [f"{r['name']} (written by implemented passes; see their references)"
                             for r in plan["resources"] if r["lifetime"] == "output"]
            elif check:
                expected = simulate(plan, frames)
                plan_size = tuple(plan.get("size") or (64, 64))
                for key, raw in sorted(data.items(), key=lambda kv: (kv[0][0], kv[0][1] or 0, kv[0][2] or 0)):
                    name, mip, layer = key
                    res = next(r for r in plan["resources"] if r["name"] == name)
                    want = expected.get(key)
                    if want is None or (res["kind"] == "image" and codec(res["format"]) is None):
                        unchecked.append(f"{name}" + (f" mip {mip} layer {layer}" if mip is not None else ""))
                        continue
                    if res["kind"] == "image":
                        mm = compare_image(res, (mip, layer), raw, want)
                        if mm:
                            mismatches.append(mm)
                    else:
                        mismatches += compare_buffer(res, raw, want, plan_size)
                data_ok = not mismatches
            if out_png is not None:
                images = [r for r in plan["resources"] if r["lifetime"] == "output" and r["kind"] == "image"]
                if not images:
                    raise ExecutionError("--out: the plan has no output image")
                res = images[0]
                w, h = mip_extent(res, 0)
                write_png(Path(out_png), _png_rgba(res, data[(res["name"], 0, 0)], w, h, bool(implemented)))
    finally:
        params_read = {p.setup.name: sorted(p.setup.params.read) for p in executor.passes if isinstance(p, ImplPass)}
        messages = executor.close()
    return RunResult(list(messages), timings, data_ok, executor.device.name if executor.device else "?",
                     mismatches, unchecked, outputs, params_read)


def _png_rgba(res: dict, raw: bytes, w: int, h: int, implemented: bool) -> Any:
    """RGBA8 for a PNG: the stored bytes of an 8-bit colour image rendered by real passes,
    else the probe's value visualisation."""
    import numpy as np

    channel_order = {"r8g8b8a8": [0, 1, 2, 3], "b8g8r8a8": [2, 1, 0, 3]}
    head, _, kind = res["format"].lower().rpartition("_")
    if implemented and head in channel_order and kind in ("srgb", "unorm"):
        rgba = np.frombuffer(raw, dtype=np.uint8, count=w * h * 4).reshape(h, w, 4)[..., channel_order[head]].copy()
        rgba[..., 3] = 255
        return rgba
    return image_to_rgba8(res, raw, w, h)
