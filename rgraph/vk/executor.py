"""Execute a plan on a Vulkan device: the ``Executor`` state and ``execute_plan``.

The plan is lowered once (``rgraph.vk.lower.lower``: barrier calls, batches, semaphore edges,
submit order, as data); command buffers are recorded from that recording once per
frame-in-flight set (2) and resubmitted; per frame only the timeline values in the prebuilt
submit structs change. Passes are grouped into batches: contiguous runs (in plan order) on
one VkQueue, cut before a pass with waits and after a pass with signals; one command buffer
and one VkSubmitInfo2 per batch, submitted in the recording's order. Frames are paced by
fences (the validation layer understands fence waits).

Each job is its own module in ``rgraph.vk.runtime``: setup, one_time, commands, submits,
frames, readback, teardown. ``rgraph.api`` (``rgraph.open_device``) is the public way in.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rgraph.vk.device import Device, create_device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.impl_pass import ImplPass
from rgraph.vk.instance import Instance, ValidationMessage, batch_cuts, create_instance, submit_per_pass
from rgraph.vk.lower import LAYER_WORKAROUNDS, LoweringError, Recording, from_device, lower
from rgraph.vk.probe_rt import needs_ray_tracing, refuse_layer_for_ray_tracing
from rgraph.vk.record import BarrierBatch
from rgraph.vk.resources import HostBuffer, ResourceSet
from rgraph.vk.runtime import frames as _frames
from rgraph.vk.runtime import readback as _readback
from rgraph.vk.runtime import setup as _setup
from rgraph.vk.runtime import teardown as _teardown
from rgraph.vk.runtime.frames import FRAME_CALLS, marks_per_frame
from rgraph.vk.runtime.readback import decode_outputs
from rgraph.vk.runtime.setup import FRAMES_IN_FLIGHT

__all__ = ["FRAMES_IN_FLIGHT", "FRAME_CALLS", "Executor", "RunResult", "decode_outputs", "execute_plan",
           "marks_per_frame"]


@dataclass
class RunResult:
    messages: list[ValidationMessage]
    timings: dict[str, Any]  # {"passes": {name: median ms}, "total_ms": median, "frames": n, "cpu_frame_ms": ...}
    data_ok: bool | None  # None: not checked
    device_name: str
    mismatches: list[Any] = field(default_factory=list)  # rgraph.probe.check.Mismatch
    unchecked: list[str] = field(default_factory=list)  # outputs the data check could not predict
    # read-back outputs as shader-visible values: images (h, w, c) float32 (layers > 1: (layers, h, w, c),
    # mip 0), buffers uint8; present when asked for (read_outputs) or when checking data
    outputs: dict[str, Any] = field(default_factory=dict)
    # pass name -> the params its implementation looked up (rgraph.vk.passkit.PassParams)
    params_read: dict[str, list[str]] = field(default_factory=dict)


class Executor:
    """Owns every Vulkan object of one plan's run; ``close`` destroys them in reverse order.

    With ``device`` given (an open ``Device`` of ``instance``) the executor borrows them and
    ``close`` leaves them open; otherwise it opens an instance (``validate``) and a device
    (``device_index``) and closes them. ``workarounds``: the validation-layer rewrites the
    lowering applies (``rgraph.vk.lower.workarounds``). ``logic_hz``: scene logic on its own
    thread at that rate (``rgraph.vk.runtime.logic``), the frame loop interpolating."""

    def __init__(self, plan: dict, *, validate: bool, device_index: int | None, verbose: bool = True,
                 inputs: dict[str, Any] | None = None, one_call_per_queue: bool = True,
                 workarounds: Iterable[str] = LAYER_WORKAROUNDS, instance: Instance | None = None,
                 device: Device | None = None, external: dict[str, list[Any]] | None = None,
                 logic_hz: float | None = None) -> None:
        if plan.get("format") != "rgraph-plan/1":
            raise ExecutionError("not an rgraph plan (format != rgraph-plan/1)")
        self.source_plan = plan
        self.plan = plan
        self.verbose = verbose
        self.one_call_per_queue = one_call_per_queue
        self.inputs = dict(inputs or {})
        self.external = dict(external or {})  # resource -> caller's VkBuffer per set (rgraph.vk.resources)
        self.owns_device = device is None
        self.scene_gpu: Any = None
        self.samplers: dict[str, Any] = {}
        self.updaters: list[ImplPass] = []
        self.instance: Instance = instance if instance is not None else create_instance(validate)
        self.device: Device | None = device
        self.recording: Recording | None = None
        self.resources: ResourceSet | None = None
        self.accels: Any = None  # rgraph.vk.accel.AccelSet when the plan has accels
        self.passes: list[ImplPass] = []
        self.pools: dict[tuple[int, int], Any] = {}
        self.query_pools: list[Any] = []
        self.command_buffers: list[list[Any]] = []  # per set, per batch
        self.fences: list[list[Any]] = []
        self.fence_arrays: list[Any] = []
        self.semaphores: list[Any] = []
        self.submit_calls: list[list[Any]] = []
        self.value_slots: list[list[tuple[Any, int]]] = []
        self.layer_edges = 0  # semaphore edges added only to avoid the 1.3.239 layer's racing false positive
        self.host_buffers: list[HostBuffer] = []
        # host buffers reused by later read-backs and receives ((purpose, resource) -> buffer;
        # also in host_buffers for teardown): the staged multi-device path moves tiles every frame
        self.staging: dict[tuple[str, str], HostBuffer] = {}
        # per set, per pass: (barrier batches before, after), the structs its command buffers point into
        self.barrier_batches_of: dict[int, dict[int, tuple[list[BarrierBatch], list[BarrierBatch]]]] = {}
        self.frames_done = 0
        # frames_done at the first frame whose content is frame 0 (``Executable.warm_up`` moves it
        # past warm-up frames of a plan that carries no state between frames)
        self.frame_origin = 0
        self.logic: Any = None  # rgraph.vk.runtime.logic.LogicThread with logic_hz (run_frames starts it)
        self.timestamp_every = 1  # read one use in this many of a frame set's timestamps (rgraph.vk.runtime.frames)
        self.host_query_reset = True  # the frame loop resets the query pools (commands.record decides)
        try:
            if self.instance.validate:
                refuse_layer_for_ray_tracing(plan)
            if self.device is None:
                self.device = create_device(self.instance, device_index, verbose=verbose,
                                            ray_tracing=needs_ray_tracing(plan))
            elif needs_ray_tracing(plan) and "accelerationStructure" not in self.device.enabled_features:
                raise ExecutionError(f"{self.device.name} was opened without ray tracing (the plan has accels or "
                                     "raytrace passes): open_device(ray_tracing=True)")
            try:
                self.recording = lower(plan, from_device(self.device), one_batch_per_pass=submit_per_pass(self.instance.validate),
                                       workarounds=workarounds, batch_cuts=batch_cuts())
            except LoweringError as exc:
                raise ExecutionError(str(exc)) from None
            self.plan = self.recording.plan
            _setup.create(self)
            if logic_hz is not None:
                _setup.attach_logic(self, logic_hz)
        except BaseException:
            self.close()
            raise

    @property
    def log(self):
        return self.instance.log

    @property
    def batches(self) -> tuple:
        return self.recording.batches if self.recording is not None else ()

    def run_frames(self, frames: int, marks: list[float] | None = None) -> dict[str, Any]:
        """Submit ``frames`` more frames; timings (``rgraph.vk.runtime.frames.run_frames``)."""
        return _frames.run_frames(self, frames, marks)

    def read_back(self, frames: int | None = None) -> dict[tuple, bytes]:
        """Bytes of every output/persistent/imported subresource after the last frame."""
        return _readback.read_back(self, frames)

    def close(self) -> list[ValidationMessage]:
        return _teardown.close(self)


def execute_plan(plan: dict, *, validate: bool = False, frames: int = 1, device_index: int | None = None,
                 check_data: bool | None = None, out_png: Path | None = None, verbose: bool = False,
                 inputs: dict[str, Any] | None = None, read_outputs: bool = False,
                 workarounds: Iterable[str] = LAYER_WORKAROUNDS) -> RunResult:
    """Run ``plan`` for ``frames`` frames on a device of its own; check the probe's data flow
    (``rgraph.probe.check``; default: when validating); write the first output image as PNG.

    ``inputs`` fills imported/persistent resources before the first frame (raw bytes or arrays
    of shader-visible values); ``read_outputs`` returns every output, persistent and imported
    resource decoded in ``RunResult.outputs``. (``rgraph.open_device`` does the same with one
    device for several plans.)
    """
    from rgraph.api import open_device

    if frames < 1:
        raise ExecutionError("--frames must be at least 1")
    if validate:
        refuse_layer_for_ray_tracing(plan)
    with open_device(validate=validate, device=device_index, verbose=verbose,
                     ray_tracing=needs_ray_tracing(plan)) as gpu:
        exe = gpu.load(plan, inputs=inputs, workarounds=workarounds)
        result = exe.run_and_check(frames, check_data=validate if check_data is None else check_data,
                                   out_png=out_png, read_outputs=read_outputs)
        result.messages = gpu.close()  # every message of the instance, its teardown included
    return result
