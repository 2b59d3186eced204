"""Stage objects: one Vulkan instance and device, plans loaded onto it, frames run.

    import rgraph
    with rgraph.open_device(validate=True) as gpu:        # one instance + device, choice printed
        plan = rgraph.compile("surgery", size=(320, 180), device=gpu)
        exe = gpu.load(plan)                               # lowered and recorded once
        result = exe.run(frames=3)                         # timings, validation messages
        images = exe.read_outputs()                        # name -> numpy array

``gpu.load`` accepts a ``Compiled``, a typed ``Plan``, a plan dict or a plan file;
``gpu.memory_requirements()`` is the provider the compiler sizes resources with
(``compile_graph(..., memory=...)``). docs/api.md has the whole API.
Everything a device needs is closed when the ``with`` block ends; executables close first.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rgraph.vk.lower import LAYER_WORKAROUNDS, QueueLayout, Recording

#: Seconds of untimed frames before timed ones on a GPU (``Gpu.default_warmup_s``).
WARMUP_S = 0.3


@dataclass
class RunSummary:
    """What ``Executable.run`` returns: per-pass GPU medians (``timings``), the validation
    messages logged while it ran, and the frames run so far."""

    timings: dict[str, Any]
    messages: list[Any] = field(default_factory=list)
    frames: int = 0

    @property
    def clean(self) -> bool:
        return not self.messages


def plan_of(obj: Any) -> dict:
    """The plan document of a plan dict, a ``Compiled`` (``rgraph.compile``), a typed
    ``rgraph.plan.Plan``, or a plan file path (loaded through the typed loader)."""
    from rgraph.compiled import Compiled
    from rgraph.plan.model import Plan

    if isinstance(obj, dict):
        return obj
    if isinstance(obj, Compiled):
        return obj.as_dict()
    if isinstance(obj, Plan):
        return obj.to_json_dict()
    if isinstance(obj, (str, Path)):
        from rgraph.plan import load

        return load(obj).to_json_dict()
    raise TypeError(f"not a plan: {type(obj).__name__} (give a plan dict, a Compiled, a Plan or a plan file)")


class Gpu:
    """One instance and one device (``open_device``); loads plans into ``Executable``s."""

    def __init__(self, validate: bool = True, device: int | None = None, verbose: bool = True,
                 ray_tracing: bool | None = None, one_queue: bool = False) -> None:
        from rgraph.vk.device import choose_physical_device, create_device, list_physical_devices
        from rgraph.vk.instance import create_instance
        from rgraph.vk.rt_device import supported

        self.validate = validate
        self.instance = create_instance(validate)
        self._executables: list[Executable] = []
        try:
            if ray_tracing is None:  # the plans are not known yet: ray tracing whenever the device has it
                ray_tracing = supported(choose_physical_device(list_physical_devices(self.instance), device).handle)
            self.device = create_device(self.instance, device, verbose=verbose, ray_tracing=ray_tracing,
                                        one_queue=one_queue)
        except BaseException:
            self.instance.destroy()
            raise
        physical = self.device.physical
        #: the physical device chosen: index, name and type (printed when ``verbose``)
        self.choice = {"index": physical.index, "name": physical.name, "type": physical.device_type}

    @property
    def name(self) -> str:
        return self.device.name

    @property
    def messages(self) -> list[Any]:
        """Every validation message logged on this instance so far."""
        return list(self.instance.log.messages)

    @property
    def default_warmup_s(self) -> float:
        """Warm-up before timed frames: ``WARMUP_S`` on a GPU (the H200 idles at low clocks:
        its first frames ran about 3x slower), none on a CPU device (lavapipe has no clocks
        to raise, and CI time matters)."""
        return 0.0 if self.choice["type"] == "cpu" else WARMUP_S

    def memory_requirements(self) -> Any:
        """The live device's memory-requirements provider (``rgraph.vk.memreq``)."""
        from rgraph.vk.memreq import DeviceMemoryRequirements

        return DeviceMemoryRequirements(self.device)

    def queues(self) -> QueueLayout:
        from rgraph.vk.lower import from_device

        return from_device(self.device)

    def load(self, compiled: Any, *, inputs: dict[str, Any] | None = None,
             workarounds: Iterable[str] = LAYER_WORKAROUNDS, one_call_per_queue: bool = True,
             external: dict[str, list[Any]] | None = None, logic_hz: float | None = None) -> Executable:
        """Lower and record ``compiled`` (a plan dict or compiled object) once on this device.
        ``external``: buffers bound by the caller for those resources (``rgraph.vk.resources``).
        ``logic_hz``: the scene's logic on its own thread at that rate, frames interpolating
        between its last two states (``rgraph.vk.runtime.logic``)."""
        exe = Executable(self, plan_of(compiled), inputs=inputs, workarounds=workarounds,
                         one_call_per_queue=one_call_per_queue, external=external, logic_hz=logic_hz)
        self._executables.append(exe)
        return exe

    def close(self) -> list[Any]:
        """Close every executable, then the device and instance; every message logged."""
        for exe in list(self._executables):
            exe.close()
        self._executables = []
        if self.device is not None and self.device.handle is not None:
            self.instance.log.context = "teardown"
            self.device.destroy()
        if self.instance.handle is not None:
            self.instance.destroy()
        return self.messages

    def __enter__(self) -> Gpu:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def open_device(validate: bool = True, device: int | None = None, verbose: bool = True,
                ray_tracing: bool | None = None, one_queue: bool = False) -> Gpu:
    """One Vulkan instance (Khronos validation + synchronization validation when ``validate``)
    and one device (``device``: physical device index; default the first discrete, else the
    first); use as a context manager. ``ray_tracing``: enable acceleration structures and ray
    tracing pipelines (``rgraph.vk.rt_device``); None (default): whenever the physical device
    supports them, as the plans are not known yet; False: never (loading a plan with accels
    or raytrace passes is then refused). ``one_queue``: every plan queue on one VkQueue (the
    graphics+compute family's; ``rgraph.vk.device.create_device``)."""
    return Gpu(validate=validate, device=device, verbose=verbose, ray_tracing=ray_tracing, one_queue=one_queue)


class Executable:
    """A plan lowered (``recording``) and recorded once on a ``Gpu``; run it any number of times."""

    def __init__(self, gpu: Gpu, plan: dict, *, inputs: dict[str, Any] | None,
                 workarounds: Iterable[str], one_call_per_queue: bool,
                 external: dict[str, list[Any]] | None = None, logic_hz: float | None = None) -> None:
        from rgraph.vk.executor import Executor

        self.gpu = gpu
        self.source_plan = plan
        self._first_message = len(gpu.instance.log.messages)
        self.executor = Executor(plan, validate=gpu.validate, device_index=None, inputs=inputs,
                                 one_call_per_queue=one_call_per_queue, workarounds=workarounds,
                                 instance=gpu.instance, device=gpu.device, verbose=False, external=external,
                                 logic_hz=logic_hz)
        self._closed = False

    @property
    def plan(self) -> dict:
        """The plan as executed (after the lowering's plan-wide rewrites)."""
        return self.executor.plan

    @property
    def recording(self) -> Recording:
        assert self.executor.recording is not None
        return self.executor.recording

    @property
    def messages(self) -> list[Any]:
        """Validation messages logged since this plan was loaded."""
        return self.gpu.instance.log.messages[self._first_message:]

    def run(self, frames: int = 3, marks: list[float] | None = None) -> RunSummary:
        """Submit ``frames`` frames (counting on from earlier runs) and wait for them."""
        if frames < 1:
            from rgraph.vk.errors import ExecutionError

            raise ExecutionError("--frames must be at least 1")
        log = self.gpu.instance.log.messages
        first = len(log)
        timings = self.executor.run_frames(frames, marks)
        return RunSummary(timings, log[first:], self.content_frames)

    @property
    def content_frames(self) -> int:
        """Frames whose content has been rendered (frames run, less warm-up frames that do not count)."""
        return self.executor.frames_done - self.executor.frame_origin

    def warm_up(self, seconds: float, frames: int | None = None) -> int:
        """Run untimed frames for about ``seconds`` of wall time (at least one frame when
        ``seconds`` > 0) so that a GPU that idles at low clocks is at its working clocks when
        timing starts; ``frames``: exactly that many instead, whatever the wall time (sweeps:
        the same count for every setting). Returns the frames run. When the plan carries no
        state between frames (``rgraph.plan.state.carries_state``) the next frame's content is
        frame 0 again (camera, animation, probe values), so images do not depend on how many
        warm-up frames the wall time allowed; otherwise the warm-up frames count (the data
        check knows them)."""
        from rgraph.plan.state import carries_state
        from rgraph.vk.runtime.frames import run_for

        if frames is None:
            if seconds <= 0:
                return 0
            frames = run_for(self.executor.run_frames, seconds)
        elif frames > 0:
            self.executor.run_frames(frames)
        else:
            return 0
        if not carries_state(self.plan):
            self.executor.frame_origin = self.executor.frames_done
        return frames

    def read_back(self) -> dict[tuple, bytes]:
        """Raw bytes per (resource, mip, layer) of outputs, persistent and imported resources."""
        return self.executor.read_back()

    def read_outputs(self) -> dict[str, Any]:
        """Outputs, persistent and imported resources as shader-visible numpy arrays (mip 0)."""
        from rgraph.vk.runtime.readback import decode_outputs

        return decode_outputs(self.plan, self.read_back())

    def run_and_check(self, frames: int, *, check_data: bool, out_png: Path | None = None,
                      read_outputs: bool = False, warmup_s: float | None = None,
                      warmup_frames: int | None = None) -> Any:
        """Warm up (``warmup_s`` seconds, None: ``default_warmup_s`` of the device; or exactly
        ``warmup_frames`` frames: ``warm_up``), run, read
        back when needed, check the probe's data (``rgraph.probe.check``), write the PNG and
        close this executable (the device stays open): an ``rgraph.vk.executor.RunResult``
        with the messages logged from load to close."""
        from rgraph.png import first_output_image, write_output_png
        from rgraph.probe.check import check_outputs
        from rgraph.vk.errors import ExecutionError
        from rgraph.vk.executor import RunResult
        from rgraph.vk.runtime.readback import decode_outputs

        try:
            if out_png is not None and first_output_image(self.plan) is None:
                raise ExecutionError("--out: the plan has no output image")
            self.warm_up(self.gpu.default_warmup_s if warmup_s is None else warmup_s, frames=warmup_frames)
            summary = self.run(frames)
            result = RunResult([], summary.timings, None, self.gpu.name)
            if check_data or read_outputs or out_png is not None:
                data = self.read_back()
                result.outputs = decode_outputs(self.plan, data)
                if check_data:
                    verdict = check_outputs(self.plan, data, self.content_frames)
                    result.data_ok, result.mismatches, result.unchecked = (verdict.ok, verdict.mismatches,
                                                                           verdict.unchecked)
                if out_png is not None:
                    write_output_png(self.plan, data, out_png)
        finally:
            params_read = {p.setup.name: sorted(p.setup.params.read) for p in self.executor.passes
                           if p.p.get("impl")}
            messages = self.close()
        result.params_read = params_read
        result.messages = list(messages)
        return result

    def close(self) -> list[Any]:
        """Destroy this plan's objects (the device stays open); its messages."""
        if not self._closed:
            self._closed = True
            self.executor.close()
            if self in self.gpu._executables:
                self.gpu._executables.remove(self)
        return self.messages

    def __enter__(self) -> Executable:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def compile_for_device(graph: Any, device_index: int | None = None, **options: Any) -> dict:
    """``compile_graph(graph, **options)`` with sizes and alignments from the live device that
    ``open_device(device=device_index)`` opens (a plan compiled for another device's profile
    is refused by the runtime's requirements cross-check). Opens and closes its own device:
    with a ``Gpu`` at hand, pass ``memory=gpu.memory_requirements()`` instead."""
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.memreq import live_requirements

    with live_requirements(device_index) as (memory, _device):
        return compile_graph(graph, memory=memory, **options)
