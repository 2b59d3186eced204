"""``MultiExecutable``: a merged multi-device plan (``rgraph.plan.devices``) on several logical devices.

One ``rgraph.api.Gpu`` per ``--devices`` entry: its own instance, ``VkDevice``, queues,
memory and command buffers (``--devices 0,0``: two logical devices on one physical device).
Each device runs its own projection of the plan (``rgraph.plan.devices.project``).

Per frame ``n``:

1. every sending device ``d > 0`` runs its frame (tiled passes, then ``X.download``) in its
   own host thread, so the senders render concurrently; each waits for its own timeline
   (never a device idle);
2. the tiles reach device 0 by one of two transfers (``transfer``):
   - ``shared`` (VK_EXT_external_memory_host on every device, the default where offered):
     ``X.tile`` of the sender and ``X.from<d>`` of device 0 are the same host bytes
     (``rgraph.vk.multi.host_memory``), one allocation per frame-in-flight set, so the
     download writes host memory and the upload reads it: no host copy at all;
   - ``staged``: the host reads the tile buffers back (device -> host) and writes them into
     device 0's ``X.from<d>`` (``rgraph.vk.multi.receive.refill``: host -> staging -> device);
3. device 0 runs its frame: its own tiles, ``X.upload<d>`` (the plan's cross-device wait is
   this host-side ordering), the composite, everything after the cut.

``pipelined``: the senders' frame ``n + 1`` is started before device 0's frame ``n``, so
device 0's copies, composite and post-cut passes of frame ``n`` overlap the senders'
rendering of ``n + 1`` (one frame of latency for the senders' share). Frame-in-flight sets
keep the two frames apart: frame ``n`` uses set ``n % 2`` on every device (the shared
allocations are per set), and the senders' frame ``n + 2`` starts only after device 0's
frame ``n`` completed.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

from rgraph.plan import Plan, to_json_dict
from rgraph.plan.devices import devices_of, project
from rgraph.vk.multi import composite as _composite  # noqa: F401 -- registers the composite
from rgraph.vk.multi import copies as _copies  # noqa: F401 -- registers the copy passes
from rgraph.vk.multi import host_memory
from rgraph.vk.multi.receive import refill
from rgraph.vk.multi.spans import span_findings
from rgraph.vk.runtime.setup import FRAMES_IN_FLIGHT

HOST_IMPORT = host_memory.HOST_IMPORT
TRANSFERS = ("auto", "shared", "staged")


def host_import_supported(gpu: Any) -> bool:
    """Whether ``gpu``'s device has VK_EXT_external_memory_host enabled (offered)."""
    return host_memory.supported(gpu.device)


@dataclass
class FrameSample:
    """One frame: host wall time, each device's GPU span and the host interval that waited for it."""

    wall_ms: float
    device_ms: list[float]  # GPU span per device (0.0 without timestamps)
    host_ms: list[float]  # host time of each device's run(1) (submit .. fence)
    copy_ms: float  # staged: tile readback + refill on the host; shared: 0
    findings: list[str] = field(default_factory=list)  # rgraph.vk.multi.spans


@dataclass
class MultiSummary:
    frames: int
    device_ms: list[float]  # median GPU frame time per device (the executor's total_ms)
    readback_ms: float  # host: tiles device d -> host -> device 0 (median per frame; 0 when shared)
    device0_ms: float  # host: device 0's frame (median)
    frame_ms: float  # host wall time per frame (median)
    host_memory_import: list[bool]
    transfer: str = "staged"
    pipelined: bool = False
    messages: list[Any] = field(default_factory=list)
    timings: dict[str, Any] = field(default_factory=dict)  # device 0's last RunSummary.timings
    device_passes: list[dict[str, float]] = field(default_factory=list)  # last frame: pass -> GPU ms, per device
    samples: list[FrameSample] = field(default_factory=list)

    @property
    def findings(self) -> list[str]:
        return [f for s in self.samples for f in s.findings]


@dataclass
class _Sent:
    runs: list[Any]
    host_ms: list[float]
    read_ms: float
    tiles: dict[str, bytes]


class MultiExecutable:
    """A merged plan on ``len(gpus)`` logical devices (module docstring)."""

    def __init__(self, gpus: list[Any], plan: Plan, *, workarounds: Any = None, transfer: str = "auto",
                 pipelined: bool = False) -> None:
        from rgraph.vk.errors import ExecutionError

        n = devices_of(plan)
        if len(gpus) != n:
            raise ExecutionError(f"the plan is split over {n} devices, --devices names {len(gpus)}")
        if transfer not in TRANSFERS:
            raise ExecutionError(f"transfer: expected one of {', '.join(TRANSFERS)}, got {transfer!r}")
        offered = all(host_import_supported(g) for g in gpus)
        if transfer == "shared" and not offered:
            raise ExecutionError(f"transfer 'shared' needs {HOST_IMPORT} on every device")
        self.transfer = "shared" if transfer == "shared" or (transfer == "auto" and offered) else "staged"
        self.pipelined = pipelined
        self.gpus = gpus
        self.plan = plan
        self.plans = [to_json_dict(project(plan, d)) for d in range(n)]
        self._kw = {} if workarounds is None else {"workarounds": workarounds}
        self.bridges: list[host_memory.SharedHostBuffer] = []
        self.receiver: Any = None
        self.senders: list[Any] = []
        self.frames_done = 0
        self._outer = ThreadPoolExecutor(max_workers=1)
        self._inner = ThreadPoolExecutor(max_workers=max(1, n - 1))
        self.shared_error: str | None = None  # auto: why the shared allocation fell back to staged
        try:
            external = [{} for _ in range(n)]
            if self.transfer == "shared":
                try:
                    external = self._share()
                except Exception as exc:  # noqa: BLE001 -- a driver refusing the import: auto falls back
                    if transfer == "shared":
                        raise ExecutionError(f"the shared host allocation was refused: {type(exc).__name__}: "
                                             f"{exc}") from exc
                    for bridge in self.bridges:
                        bridge.destroy()
                    self.bridges, self.transfer, self.shared_error = [], "staged", f"{type(exc).__name__}: {exc}"
            self.senders = [gpus[d].load(self.plans[d], external=external[d], **self._kw) for d in range(1, n)]
            if self.transfer == "shared":
                self.receiver = gpus[0].load(self.plans[0], external=external[0], **self._kw)
        except BaseException:
            self.close()
            raise

    def _share(self) -> list[dict[str, list[Any]]]:
        """One shared host allocation per (sender, crossing resource, frame set): the sender's
        ``X.tile`` and device 0's ``X.from<d>`` bound to the same bytes."""
        external: list[dict[str, list[Any]]] = [{} for _ in self.gpus]
        res = [{r["name"]: r for r in p["resources"]} for p in self.plans]
        for d in range(1, len(self.gpus)):
            for x in self.plan.multi_device["crossing"]:
                tile, landing = res[d][f"{x}.tile"], res[0][f"{x}.from{d}"]
                for _s in range(FRAMES_IN_FLIGHT):
                    bridge = host_memory.SharedHostBuffer.create(
                        int(tile["size_bytes"] or tile["bytes"]),
                        [(self.gpus[d].device, tile["usages"]), (self.gpus[0].device, landing["usages"])])
                    self.bridges.append(bridge)
                    external[d].setdefault(tile["name"], []).append(bridge.buffers[0])
                    external[0].setdefault(landing["name"], []).append(bridge.buffers[1])
        return external

    def _send_one(self, d: int, exe: Any) -> tuple[Any, float, float, dict[str, bytes]]:
        t0 = time.perf_counter()
        summary = exe.run(1)
        t1 = time.perf_counter()
        tiles: dict[str, bytes] = {}
        if self.transfer == "staged":  # the readback buffers are the executor's, reused every frame
            for (name, _mip, _layer), raw in exe.read_back().items():
                if name.endswith(".tile"):
                    tiles[f"{name[:-len('.tile')]}.from{d}"] = raw
        return summary, (t1 - t0) * 1e3, (time.perf_counter() - t1) * 1e3, tiles

    def _send(self) -> _Sent:
        jobs = [self._inner.submit(self._send_one, d, exe) for d, exe in enumerate(self.senders, start=1)]
        done = [j.result() for j in jobs]
        tiles: dict[str, bytes] = {}
        for r in done:
            tiles.update(r[3])
        return _Sent([r[0] for r in done], [r[1] for r in done], max((r[2] for r in done), default=0.0), tiles)

    def _receive(self, sent: _Sent) -> None:
        if self.transfer == "shared":
            return
        if self.receiver is None:
            have = {r["name"] for r in self.plans[0]["resources"]}
            missing = sorted(set(sent.tiles) - have)
            if missing:
                from rgraph.vk.errors import ExecutionError

                raise ExecutionError(f"device 0's plan has no receiving buffer(s) {missing}")
            self.receiver = self.gpus[0].load(self.plans[0], inputs=sent.tiles, **self._kw)
            self.receiver.executor.frames_done = self.frames_done  # in step with the senders (seek)
        else:
            refill(self.receiver, sent.tiles)

    def warm_up(self, seconds: float) -> int:
        """Untimed frames for about ``seconds`` (``rgraph.api.Executable.warm_up``); the frames run."""
        from rgraph.vk.runtime.frames import run_for

        return run_for(self.run, seconds) if seconds > 0 else 0

    def seek(self, frame: int) -> None:
        """Continue at frame ``frame`` on every device (frame-dependent values, frame sets):
        ``DynamicBalance`` switching between the executables of band layouts. Every earlier
        frame of these executables has completed (``run`` waits for them)."""
        self.frames_done = frame
        for exe in [*self.senders, self.receiver]:
            if exe is not None:
                exe.executor.frames_done = frame

    def run(self, frames: int = 1) -> MultiSummary:
        """``frames`` frames on every device (module docstring); every frame has completed on return."""
        if frames < 1:
            from rgraph.vk.errors import ExecutionError

            raise ExecutionError("--frames must be at least 1")
        samples: list[FrameSample] = []
        pending = None
        summary = runs = None
        for i in range(frames):
            t0 = time.perf_counter()
            sent = (pending or self._outer.submit(self._send)).result()  # the senders' frame i
            more = self.pipelined and i + 1 < frames
            pending = self._outer.submit(self._send) if more else None  # frame i + 1 overlaps device 0's frame i
            t1 = time.perf_counter()
            self._receive(sent)
            t2 = time.perf_counter()
            summary = self.receiver.run(1)
            t3 = time.perf_counter()
            self.frames_done += 1
            runs = sent.runs
            spans = [summary.timings.get("total_ms") or 0.0] + [r.timings.get("total_ms") or 0.0 for r in runs]
            hosts = [(t3 - t2) * 1e3] + sent.host_ms
            findings = [f for d, (exe, r) in enumerate(zip([self.receiver, *self.senders], [summary, *runs],
                                                           strict=True))
                        for f in span_findings(d, exe.plan, r.timings, hosts[d])]
            copy = sent.read_ms + (t2 - t1) * 1e3 if self.transfer == "staged" else 0.0
            samples.append(FrameSample((t3 - t0) * 1e3, spans, hosts, copy, findings))
        assert summary is not None and runs is not None
        passes = [dict(summary.timings.get("passes", {}))] + [dict(r.timings.get("passes", {})) for r in runs]
        n = len(self.gpus)
        return MultiSummary(frames, [_median([s.device_ms[d] for s in samples]) for d in range(n)],
                            _median([s.copy_ms for s in samples]), _median([s.host_ms[0] for s in samples]),
                            _median([s.wall_ms for s in samples]), [host_import_supported(g) for g in self.gpus],
                            transfer=self.transfer, pipelined=self.pipelined, timings=summary.timings,
                            device_passes=passes, samples=samples)

    def read_back(self) -> dict[tuple, bytes]:
        """Device 0's outputs (the composited frame) as ``Executable.read_back`` (once per run)."""
        assert self.receiver is not None and self.frames_done, "run first"
        return self.receiver.read_back()

    def read_outputs(self) -> dict[str, Any]:
        """``read_back`` decoded (instead of it, not after it)."""
        from rgraph.vk.runtime.readback import decode_outputs

        return decode_outputs(self.plans[0], self.read_back())

    def close(self) -> None:
        self._outer.shutdown(wait=True)
        self._inner.shutdown(wait=True)
        for exe in self.senders:
            exe.close()
        if self.receiver is not None:
            self.receiver.close()
        self.senders, self.receiver = [], None
        for bridge in self.bridges:
            bridge.destroy()
        self.bridges = []


def _median(values: list[float]) -> float:
    s = sorted(values)
    return s[len(s) // 2] if s else 0.0
