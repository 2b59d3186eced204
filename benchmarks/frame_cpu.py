"""Per-frame CPU cost of resubmitting a compiled plan, and GPU busy fraction at 1920x1080.

CPU: main-thread CPU time (time.thread_time) between consecutive frame starts of one run of
the surgery plan (no validation), median over many frames; target <= 50 us. The driver's own
worker threads are not counted, so this is what Python, the binding and the submit calls cost.

GPU busy (GPU devices only): per frame, the GPU time of the passes (timestamps) over the frame's
wall time (perf_counter over many pipelined frames). Two figures: the span from the first
pass's start to the last pass's end (gaps between passes count as busy), and the sum of the
per-pass times capped at the span (gaps excluded when passes do not overlap); target >= 95%.

    python benchmarks/frame_cpu.py [--frames 2000] [--busy-frames 300] [--size 64x64]
"""

from __future__ import annotations

import argparse
import re
import statistics
import time

from rgraph.compile.pipeline import compile_graph
from rgraph.vk.device import create_device
from rgraph.vk.executor import Executor
from rgraph.vk.instance import create_instance
from rgraph.vk.memreq import DeviceMemoryRequirements


def compile_for_device(size: tuple[int, int], policy: str | None = None) -> tuple[dict, str, bool]:
    instance = create_instance(validate=False)
    try:
        device = create_device(instance, None, verbose=False)
        try:
            plan = compile_graph("surgery", size=size, policy=policy, memory=DeviceMemoryRequirements(device))
            return plan, device.name, device.physical.device_type != "cpu"
        finally:
            device.destroy()
    finally:
        instance.destroy()


def frame_cpu_us(plan: dict, frames: int) -> list[float]:
    """Main-thread CPU microseconds of each frame (frame start to next frame start)."""
    executor = Executor(plan, validate=False, device_index=None, verbose=False)
    marks: list[float] = []
    log = executor.log
    base = type(log)

    class Marking(base):  # type: ignore[misc, valid-type]
        def __setattr__(self, name, value):
            if name == "context" and isinstance(value, str) and re.fullmatch(r"frame \d+", value):
                marks.append(time.thread_time())
            base.__setattr__(self, name, value)

    log.__class__ = Marking
    try:
        executor.run_frames(frames)
    finally:
        log.__class__ = base
        executor.close()
    return [(b - a) * 1e6 for a, b in zip(marks, marks[1:], strict=False)][10:]  # skip warm-up


def gpu_busy(plan: dict, frames: int) -> dict[str, float]:
    executor = Executor(plan, validate=False, device_index=None, verbose=False)
    try:
        executor.run_frames(20)  # warm-up (pipelines, caches, clocks)
        t0 = time.perf_counter()
        timings = executor.run_frames(frames)
        wall_ms = (time.perf_counter() - t0) * 1000.0 / frames
    finally:
        executor.close()
    span = timings["total_ms"] or 0.0
    summed = min(sum(v for v in timings["passes"].values() if v is not None), span)
    return {"wall_ms": wall_ms, "span_ms": span, "sum_ms": summed, "span_fraction": span / wall_ms,
            "sum_fraction": summed / wall_ms, "cpu_submit_ms": timings["cpu_submit_ms"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=2000)
    parser.add_argument("--busy-frames", type=int, default=300)
    parser.add_argument("--size", default="64x64", help="size for the CPU measurement (default 64x64)")
    parser.add_argument("--policy", default=None, help="memory placement policy (default: the compiler's)")
    args = parser.parse_args()
    w, h = (int(x) for x in args.size.lower().split("x"))
    plan, device, is_gpu = compile_for_device((w, h), args.policy)
    per_frame = frame_cpu_us(plan, args.frames)
    passes = len(plan["passes"])
    print(f"device: {device}")
    print(f"surgery {w}x{h}: {passes} passes, {sum(len(p['barriers']) for p in plan['passes'])} barriers")
    print(f"frame CPU (main thread, {len(per_frame)} frames): median {statistics.median(per_frame):.1f} us, "
          f"p10 {statistics.quantiles(per_frame, n=10)[0]:.1f} us, p90 {statistics.quantiles(per_frame, n=10)[-1]:.1f} us"
          f" (target <= 50 us)")
    if not is_gpu:
        print("GPU busy fraction: skipped (CPU device: lavapipe runs the frame on CPU threads)")
        return
    plan1080, _, _ = compile_for_device((1920, 1080), args.policy)
    busy = gpu_busy(plan1080, args.busy_frames)
    print(f"surgery 1920x1080, {args.busy_frames} frames: wall {busy['wall_ms']:.3f} ms/frame, GPU span "
          f"{busy['span_ms']:.3f} ms, GPU pass sum {busy['sum_ms']:.3f} ms, submit CPU {busy['cpu_submit_ms']:.3f} ms")
    print(f"GPU busy fraction: span/wall {100 * busy['span_fraction']:.1f}%, sum/wall "
          f"{100 * busy['sum_fraction']:.1f}% (target >= 95%)")


if __name__ == "__main__":
    main()
