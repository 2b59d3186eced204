"""One benchmark configuration of benchmarks/multi_gpu.py (one device, or a split with a
transfer and pipelining choice) and the way every configuration is measured the same.

Per configuration, after a warm-up of at least ``warmup_s`` seconds of frames (the H200
starts at low clocks: its first frames run about three times slower), each round runs

- ``serial`` frames: ``run(1)`` each, fenced: the GPU span of every device (its first pass
  start to its last pass end) and the frame's host wall time; every span is checked to cover
  all of its device's passes and to lie inside the host interval that waited for it
  (``rgraph.vk.multi.spans``);
- ``stream`` frames: ``run(k)``: frames as the runtime overlaps them (one device: two frames
  in flight; a split: pipelined or not), wall time per frame = elapsed / k.

Rounds alternate configurations (``benchmarks.multi_gpu`` loops rounds outside, configurations
inside), so clock drift spreads over all of them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from rgraph.vk.multi.spans import span_findings


@dataclass
class Config:
    graph: str
    split: str | None  # None: one device
    transfer: str | None
    pipelined: bool
    runner: Any  # rgraph.api.Executable or rgraph.vk.multi.run.MultiExecutable
    plan: Any
    serial: list[dict[str, Any]] = field(default_factory=list)
    stream_ms: list[float] = field(default_factory=list)
    warmup: dict[str, float] = field(default_factory=dict)
    balance: str = "static"  # dynamic: the runner is an rgraph.vk.multi.balance.DynamicBalance

    @property
    def label(self) -> str:
        if self.split is None:
            return "one device"
        return (f"{self.split} {self.transfer}{' pipe' if self.pipelined else ''}"
                f"{' dyn' if self.balance == 'dynamic' else ''}")

    def warm(self, seconds: float) -> None:
        from rgraph.vk.runtime.frames import run_for

        t0 = time.perf_counter()
        frames = run_for(self.runner.run, seconds, min_frames=2)
        self.warmup = {"frames": frames, "seconds": time.perf_counter() - t0}

    def serial_frame(self) -> None:
        t0 = time.perf_counter()
        s = self.runner.run(1)
        wall = (time.perf_counter() - t0) * 1e3
        if self.split is None:
            span = s.timings.get("total_ms") or 0.0
            self.serial.append({"wall_ms": wall, "device_ms": [span], "copy_ms": 0.0, "composite_ms": 0.0,
                                "findings": span_findings(0, self.runner.plan, s.timings, wall)})
            return
        sample = s.samples[0]
        composite = sum(ms or 0.0 for name, ms in s.device_passes[0].items()
                        if ".upload" in name or name.startswith("composite"))
        self.serial.append({"wall_ms": wall, "device_ms": sample.device_ms, "copy_ms": sample.copy_ms,
                            "composite_ms": composite, "findings": sample.findings})

    def stream(self, frames: int) -> None:
        t0 = time.perf_counter()
        self.runner.run(frames)
        self.stream_ms.append((time.perf_counter() - t0) * 1e3 / frames)

    def row(self) -> dict[str, Any]:
        devices = len(self.serial[0]["device_ms"]) if self.serial else 1
        gpu = [_median([s["device_ms"][d] for s in self.serial]) for d in range(devices)]
        senders = max(gpu[1:], default=0.0)
        # device 0 waits for the senders' frame; pipelined, it overlaps their next one
        critical = max(gpu[0], senders) if self.pipelined else gpu[0] + senders
        return {"graph": self.graph, "config": self.label, "split": self.split, "transfer": self.transfer,
                "pipelined": self.pipelined, "gpu_ms": gpu, "critical_ms": critical,
                "serial_wall_ms": _median([s["wall_ms"] for s in self.serial]),
                "stream_wall_ms": _median(self.stream_ms),
                "copy_ms": _median([s["copy_ms"] for s in self.serial]),
                "composite_ms": _median([s["composite_ms"] for s in self.serial]),
                "frames": len(self.serial),
                "stream_batches": len(self.stream_ms), "warmup": self.warmup,
                "findings": sorted({f for s in self.serial for f in s["findings"]}),
                "cut": (self.plan.multi_device or {}).get("cut") if self.split else None, "balance": self.balance,
                "plan_loads": getattr(self.runner, "loads", 1),
                "bands": [list(r) for r in getattr(self.runner, "layouts", [])[-1:]]}

    def close(self) -> None:
        self.runner.close()


def _median(values: list[float]) -> float:
    s = sorted(values)
    return s[len(s) // 2] if s else 0.0
