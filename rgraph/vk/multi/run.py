"""``MultiExecutable``: a merged multi-device plan (``rgraph.plan.devices``) on several logical devices.

One ``rgraph.api.Gpu`` per ``--devices`` entry: its own instance, ``VkDevice``, queues,
memory and command buffers (``--devices 0,0``: two logical devices on one physical device).
Each device runs its own projection of the plan (``rgraph.plan.devices.project``).

Per frame, in this order (v1, staged path):

1. every sending device ``d > 0`` submits its frame (tiled passes, then ``X.download``
   into its tile buffer) -- they run concurrently with each other;
2. the host waits for each sender's frame (its timeline values: the executor waits per
   device, never a device-wide idle) and reads the tile buffers back (device -> host);
3. device 0 receives them into its ``X.from<d>`` buffers (host -> staging -> device: at
   load for the first frame, then ``rgraph.vk.multi.receive.refill``, one fenced one-time
   submit) and runs its frame: its own tiles, ``X.upload<d>`` (the cross-device wait of
   the plan is this host-side ordering), then everything after the composite.

Not yet: ``VK_EXT_external_memory_host`` (one host allocation imported by both devices);
``host_memory_import`` in the summary says whether each device offers it. Device 0 starts
its frame after the senders' frames end (no overlap across devices yet, no frame of
latency); the timings separate render, copy and composite.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from rgraph.plan import Plan, to_json_dict
from rgraph.plan.devices import devices_of, project
from rgraph.vk.multi import composite as _composite  # noqa: F401 -- registers the composite
from rgraph.vk.multi import copies as _copies  # noqa: F401 -- registers the copy passes
from rgraph.vk.multi.receive import refill

HOST_IMPORT = "VK_EXT_external_memory_host"


def host_import_supported(gpu: Any) -> bool:
    """Whether ``gpu``'s physical device offers VK_EXT_external_memory_host."""
    from rgraph.vk.loader import vk

    v = vk()
    props = v.vkEnumerateDeviceExtensionProperties(gpu.device.physical.handle, None)
    names = {p.extensionName if isinstance(p.extensionName, str) else v.ffi.string(p.extensionName).decode()
             for p in props}
    return HOST_IMPORT in names


@dataclass
class MultiSummary:
    frames: int
    device_ms: list[float]  # median GPU frame time per device (the executor's total_ms)
    readback_ms: float  # host: tile buffers device d -> host (median per frame, all senders)
    device0_ms: float  # host: device 0's load + frame, received bytes included (median per frame)
    frame_ms: float  # host wall time per frame (median)
    host_memory_import: list[bool]
    messages: list[Any] = field(default_factory=list)
    timings: dict[str, Any] = field(default_factory=dict)  # device 0's last RunSummary.timings
    device_passes: list[dict[str, float]] = field(default_factory=list)  # last frame: pass -> GPU ms, per device


class MultiExecutable:
    """A merged plan on ``len(gpus)`` logical devices (module docstring)."""

    def __init__(self, gpus: list[Any], plan: Plan, *, workarounds: Any = None) -> None:
        n = devices_of(plan)
        if len(gpus) != n:
            from rgraph.vk.errors import ExecutionError

            raise ExecutionError(f"the plan is split over {n} devices, --devices names {len(gpus)}")
        self.gpus = gpus
        self.plan = plan
        self.plans = [to_json_dict(project(plan, d)) for d in range(n)]
        self.workarounds = workarounds
        kw = {} if workarounds is None else {"workarounds": workarounds}
        self._kw = kw
        self.senders = [gpus[d].load(self.plans[d], **kw) for d in range(1, n)]
        self.receiver: Any = None
        self.frames_done = 0

    def _received(self) -> dict[str, bytes]:
        out: dict[str, bytes] = {}
        for d, exe in enumerate(self.senders, start=1):
            data = exe.read_back()
            for (name, _mip, _layer), raw in data.items():
                if name.endswith(".tile"):
                    out[f"{name[:-len('.tile')]}.from{d}"] = raw
        return out

    def run(self, frames: int = 1) -> MultiSummary:
        walls, reads, zeros, per_device = [], [], [], [[] for _ in self.gpus]
        summary = None
        for _ in range(frames):
            t0 = time.perf_counter()
            runs = [exe.run(1) for exe in self.senders]
            t1 = time.perf_counter()
            received = self._received()
            t2 = time.perf_counter()
            if self.receiver is None:
                have = {r["name"] for r in self.plans[0]["resources"]}
                missing = sorted(set(received) - have)
                if missing:
                    from rgraph.vk.errors import ExecutionError

                    raise ExecutionError(f"device 0's plan has no receiving buffer(s) {missing}")
                self.receiver = self.gpus[0].load(self.plans[0], inputs=received, **self._kw)
            else:
                refill(self.receiver, received)
            summary = self.receiver.run(1)
            t3 = time.perf_counter()
            self.frames_done += 1
            walls.append((t3 - t0) * 1e3)
            reads.append((t2 - t1) * 1e3)
            zeros.append((t3 - t2) * 1e3)
            per_device[0].append(summary.timings.get("total_ms") or 0.0)
            for d, r in enumerate(runs, start=1):
                per_device[d].append(r.timings.get("total_ms") or 0.0)
        assert summary is not None
        passes = [dict(summary.timings.get("passes", {}))] + [dict(r.timings.get("passes", {})) for r in runs]
        return MultiSummary(frames, [_median(x) for x in per_device], _median(reads), _median(zeros), _median(walls),
                            [host_import_supported(g) for g in self.gpus], timings=summary.timings,
                            device_passes=passes)

    def read_back(self) -> dict[tuple, bytes]:
        """Device 0's outputs (the composited frame) as ``Executable.read_back`` (once per run)."""
        assert self.receiver is not None, "run first"
        return self.receiver.read_back()

    def read_outputs(self) -> dict[str, Any]:
        """``read_back`` decoded (instead of it, not after it)."""
        from rgraph.vk.runtime.readback import decode_outputs

        return decode_outputs(self.plans[0], self.read_back())

    def close(self) -> None:
        for exe in self.senders:
            exe.close()
        if self.receiver is not None:
            self.receiver.close()


def _median(values: list[float]) -> float:
    s = sorted(values)
    return s[len(s) // 2] if s else 0.0
