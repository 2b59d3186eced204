"""Per-frame CPU cost of resubmitting a compiled plan, and GPU busy fraction at 1920x1080.

CPU: the main thread's wall time (time.perf_counter) between consecutive frame starts of the
surgery plan (no validation), median over many frames, split by marks around every Vulkan
call of the frame loop (``Executor.run_frames``) into: blocked (the vkWaitForFences call: the
CPU is ahead of the GPU and waits for the frame two back), the other Vulkan calls (timestamp
read, fence and query resets, the vkQueueSubmit2 calls: driver time), and Python - everything
else: updates (scene animation and pass ``update`` hooks: with ``--passes real`` the pass
implementations' cost), semaphore values, the loop itself; target <= 50 us. The runtime is
Python plus the Vulkan calls. The first measurement is followed by ``--rounds`` rounds that
alternate one vkQueueSubmit2 per VkQueue (the default) with one per run of batches.

``--passes probe`` (default) runs every pass with the probe implementation, so the figure is
the runtime's resubmission cost alone; ``--passes real`` keeps the graph's implementations
(target <= 150 us of Python per frame at 1920x1080: ``--size 1920x1080 --passes real``; the
deformable neck's normals and tangents are a compute pass, the CPU writes its positions) and
prints the per-frame host updates one by one (``update_costs``: the scene's, each pass's).
``--logic-hz HZ`` runs the scene's logic on its own thread (``rgraph.vk.runtime.logic``) and
measures the render thread the same way.

GPU busy (GPU devices only): per frame, the GPU time of the passes (timestamps) over the frame's
wall time (perf_counter over many pipelined frames). Two figures: the span from the first
pass's start to the last pass's end (gaps between passes count as busy), and the sum of the
per-pass times capped at the span (gaps excluded when passes do not overlap); target >= 95%.

``--compare-sync WxH`` instead compares the normal plan with ``--sync naive`` (a full
barrier before every pass, one queue, no semaphores) at that size, in one process:
rounds alternate the two plans; each reports wall ms per frame over ``--busy-frames``
pipelined frames and the GPU span (first pass start to last pass end, median).

    python benchmarks/frame_cpu.py [--frames 2000] [--busy-frames 300] [--size 64x64]
        [--policy P] [--passes probe|real] [--logic-hz HZ] [--timestamps-every K]
        [--compare-sync 1920x1080 [--rounds 3]]
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import rgraph
from rgraph.compiler.pipeline import compile_graph
from rgraph.vk.executor import FRAME_CALLS, marks_per_frame


def compile_for_device(gpu: rgraph.Gpu, size: tuple[int, int], policy: str | None = None, graph: str = "surgery",
                       sync: str | None = None) -> tuple[dict, str, bool]:
    plan = compile_graph(graph, size=size, policy=policy, memory=gpu.memory_requirements(),
                         **({"sync": sync} if sync else {}))
    return plan, gpu.name, gpu.choice["type"] != "cpu"


def probe_only(plan: dict) -> dict:
    """The plan with every pass run by the probe implementation (no per-frame pass updates)."""
    return {**plan, "passes": [{**p, "impl": None} for p in plan["passes"]]}


def frame_cpu_us(gpu: rgraph.Gpu, plan: dict, frames: int, one_call_per_queue: bool = True,
                 logic_hz: float | None = None, timestamps_every: int = 1) -> dict[str, Any]:
    """Per frame (microseconds, frame start to next frame start): blocked in the fence wait,
    each Vulkan call, and Python (the rest); ``calls``: vkQueueSubmit2 calls per frame;
    ``render_thread``/``logic``: the run's timings of them (thread CPU time per frame)."""
    marks: list[float] = []
    with gpu.load(plan, one_call_per_queue=one_call_per_queue, logic_hz=logic_hz) as exe:
        exe.executor.timestamp_every = timestamps_every
        timings = exe.run(frames, marks=marks).timings
        calls = len(exe.executor.submit_calls[0])
    parts = frame_parts(marks, calls)
    parts["render_thread"], parts["logic"] = timings.get("render_thread"), timings.get("logic")
    return parts


def frame_parts(marks: list[float], calls: int, skip: int = 10) -> dict[str, Any]:
    """Split ``Executor.run_frames`` marks into per-frame parts (``skip`` warm-up frames)."""
    m = marks_per_frame(calls)
    frames = [marks[i:i + m] for i in range(0, len(marks), m)]
    parts: dict[str, Any] = {"calls": calls, "frame": [], "gpu_wait": [], "runtime": [], "python": [],
                             "vulkan": [], "submit": [], **{name: [] for name in FRAME_CALLS[1:]}}
    for this, nxt in zip(frames[skip:], frames[skip + 1:], strict=False):
        pairs = [(this[1 + 2 * k], this[2 + 2 * k]) for k in range(len(FRAME_CALLS) + calls)]
        spans = [(b - a) * 1e6 for a, b in pairs]
        frame = (nxt[0] - this[0]) * 1e6
        blocked, others = spans[0], spans[1:]
        parts["frame"].append(frame)
        parts["gpu_wait"].append(blocked)
        parts["runtime"].append(frame - blocked)
        parts["vulkan"].append(sum(others))
        parts["python"].append(frame - blocked - sum(others))
        for name, span in zip(FRAME_CALLS[1:], others, strict=False):
            parts[name].append(span)
        parts["submit"].append(sum(others[len(FRAME_CALLS) - 1:]))
    return parts


def update_costs(gpu: rgraph.Gpu, plan: dict, frames: int) -> dict[str, float]:
    """Median microseconds of each per-frame host update (what ``run_frames`` calls between the
    fence wait and the submits), timed one by one outside the frame loop."""
    perf = time.perf_counter
    out: dict[str, float] = {}
    with gpu.load(plan) as exe:
        ex = exe.executor
        hooks = ([("scene", ex.scene_gpu.update)] if ex.scene_gpu is not None else [])
        if ex.scene_gpu is not None and ex.scene_gpu.deform is not None:
            hooks.append(("  of it: deformable positions", lambda f, s: ex.scene_gpu.deform.write(f / 60.0, s)))
        hooks += [(f"pass {p.setup.name}", p.update) for p in ex.updaters]
        for name, hook in hooks:
            spans = []
            for f in range(frames):
                t0 = perf()
                hook(f, f % 2)
                spans.append((perf() - t0) * 1e6)
            out[name] = statistics.median(spans[10:] or spans)
    return out


def gpu_busy(gpu: rgraph.Gpu, plan: dict, frames: int) -> dict[str, float]:
    with gpu.load(plan) as exe:
        exe.run(20)  # warm-up (pipelines, caches, clocks)
        t0 = time.perf_counter()
        timings = exe.run(frames).timings
        wall_ms = (time.perf_counter() - t0) * 1000.0 / frames
    span = timings["total_ms"] or 0.0
    summed = min(sum(v for v in timings["passes"].values() if v is not None), span)
    return {"wall_ms": wall_ms, "span_ms": span, "sum_ms": summed, "span_fraction": span / wall_ms,
            "sum_fraction": summed / wall_ms, "cpu_submit_ms": timings["cpu_submit_ms"]}


def compare_sync(gpu: rgraph.Gpu, size: tuple[int, int], frames: int, policy: str | None, passes: str,
                 rounds: int) -> None:
    plans = {}
    for mode in ("normal", "naive"):
        plan, device, _ = compile_for_device(gpu, size, policy, sync=mode)
        plans[mode] = probe_only(plan) if passes == "probe" else plan
    print(f"device: {device}")
    print(f"surgery {size[0]}x{size[1]} ({passes} passes), {frames} frames per round; normal: "
          f"{plans['normal']['stats']['barriers']} barriers, {plans['normal']['stats']['semaphores']} semaphores, "
          f"queues {plans['normal']['queues']}; naive: {plans['naive']['stats']['barriers']} barriers, one queue")
    results: dict[str, list[dict[str, float]]] = {"normal": [], "naive": []}
    for r in range(rounds):
        for mode in ("normal", "naive") if r % 2 == 0 else ("naive", "normal"):
            busy = gpu_busy(gpu, plans[mode], frames)
            results[mode].append(busy)
            print(f"  round {r} {mode:6s}: wall {busy['wall_ms']:.3f} ms/frame, GPU span {busy['span_ms']:.3f} ms")
    wall = {m: statistics.median(b["wall_ms"] for b in v) for m, v in results.items()}
    span = {m: statistics.median(b["span_ms"] for b in v) for m, v in results.items()}
    print(f"median of rounds: normal wall {wall['normal']:.3f} ms, span {span['normal']:.3f} ms; naive wall "
          f"{wall['naive']:.3f} ms, span {span['naive']:.3f} ms; naive/normal wall {wall['naive'] / wall['normal']:.3f}, "
          f"span {span['naive'] / span['normal']:.3f}")


def _summary(values: list[float]) -> str:
    deciles = statistics.quantiles(values, n=10)
    return (f"median {statistics.median(values):.1f} us, p10 {deciles[0]:.1f} us, p90 {deciles[-1]:.1f} us, "
            f"mean {statistics.fmean(values):.1f} us")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=2000)
    parser.add_argument("--busy-frames", type=int, default=300)
    parser.add_argument("--size", default="64x64", help="size for the CPU measurement (default 64x64)")
    parser.add_argument("--policy", default=None, help="memory placement policy (default: the compiler's)")
    parser.add_argument("--passes", choices=("probe", "real"), default="probe",
                        help="probe: every pass by the probe (the runtime's own cost); real: the graph's passes")
    parser.add_argument("--logic-hz", type=float, default=None,
                        help="scene logic on its own thread at this rate (rgraph run --logic-hz)")
    parser.add_argument("--timestamps-every", dest="timestamps_every", type=int, default=1,
                        help="the frame loop reads one frame's timestamps in this many (default 1: every frame)")
    parser.add_argument("--compare-sync", metavar="WxH", help="compare normal and --sync naive plans at this size")
    parser.add_argument("--rounds", type=int, default=3,
                        help="rounds of the CPU measurement and of --compare-sync (default 3)")
    args = parser.parse_args()
    with rgraph.open_device(validate=False, verbose=False) as gpu:  # one device for every measurement
        measure(gpu, args)


def measure(gpu: rgraph.Gpu, args: argparse.Namespace) -> None:
    if args.compare_sync:
        cw, ch = (int(x) for x in args.compare_sync.lower().split("x"))
        compare_sync(gpu, (cw, ch), args.busy_frames, args.policy, args.passes, args.rounds)
        return
    w, h = (int(x) for x in args.size.lower().split("x"))
    plan, device, is_gpu = compile_for_device(gpu, (w, h), args.policy)
    if args.passes == "probe":
        plan = probe_only(plan)
    parts = frame_cpu_us(gpu, plan, args.frames, logic_hz=args.logic_hz, timestamps_every=args.timestamps_every)
    passes = len(plan["passes"])
    print(f"device: {device}")
    logic = f", logic thread at {args.logic_hz:g} Hz" if args.logic_hz else ""
    logic += f", timestamps read every {args.timestamps_every} frames" if args.timestamps_every > 1 else ""
    print(f"surgery {w}x{h} ({args.passes} passes{logic}): {passes} passes, "
          f"{sum(len(p['barriers']) for p in plan['passes'])} barriers")
    print(f"frame wall time, main thread ({len(parts['frame'])} frames): {_summary(parts['frame'])}")
    print(f"  blocked in vkWaitForFences (GPU still busy):       {_summary(parts['gpu_wait'])}")
    print(f"  runtime (frame minus the fence wait):              {_summary(parts['runtime'])}")
    target = 50 if args.passes == "probe" else 150
    print(f"    Python (runtime minus Vulkan calls):             {_summary(parts['python'])} (target <= {target} us)")
    print(f"    Vulkan calls (driver):                           {_summary(parts['vulkan'])}")
    for name in FRAME_CALLS[1:]:
        print(f"      {name + ':':<47}{_summary(parts[name])}")
    calls = f"      vkQueueSubmit2 ({parts['calls']} calls per frame):"
    print(f"{calls:<53}{_summary(parts['submit'])}")
    render = parts["render_thread"] or {}
    print(f"  render thread CPU time (time.thread_time, driver calls included): "
          f"{render.get('cpu_us_per_frame', 0.0):.1f} us per frame; host updates {render.get('update_us', 0.0):.1f} us median")
    if parts["logic"]:
        lg = parts["logic"]
        print(f"  logic thread: {lg['ticks']} ticks at {lg['hz']:g} Hz (measured {lg['measured_hz'] or 0:.1f} Hz, "
              f"{lg['late_ticks']} late), median tick {lg['tick_us'] or 0:.1f} us, alpha in {lg['alpha_range']}")
    if args.passes == "real":
        print("  per-frame host updates, each timed alone (median):")
        for name, us in update_costs(gpu, plan, min(args.frames, 500)).items():
            print(f"      {name + ':':<47}{us:.1f} us")
    rounds = {"per queue": [parts], "per run": []}
    for r in range(args.rounds):  # same process: rounds alternate one call per queue / per run of batches
        for mode in ("per run", "per queue") if r % 2 == 0 else ("per queue", "per run"):
            if r or mode == "per run":
                rounds[mode].append(frame_cpu_us(gpu, plan, args.frames, one_call_per_queue=mode == "per queue",
                                                 logic_hz=args.logic_hz, timestamps_every=args.timestamps_every))
    for mode, measured in rounds.items():
        python = [statistics.median(m["python"]) for m in measured]
        runtime = [statistics.median(m["runtime"]) for m in measured]
        print(f"  one call {mode} ({measured[0]['calls']} calls), {len(measured)} rounds: median Python "
              + ", ".join(f"{x:.1f}" for x in python) + " us; median runtime "
              + ", ".join(f"{x:.1f}" for x in runtime) + " us")
    ratio = (statistics.median(statistics.median(m["runtime"]) for m in rounds["per queue"])
             / statistics.median(statistics.median(m["runtime"]) for m in rounds["per run"]))
    print(f"  runtime per-queue/per-run (median of round medians): {ratio:.2f}")
    if not is_gpu:
        print("GPU busy fraction: skipped (CPU device: lavapipe runs the frame on CPU threads)")
        return
    plan1080, _, _ = compile_for_device(gpu, (1920, 1080), args.policy)
    if args.passes == "probe":
        plan1080 = probe_only(plan1080)
    busy = gpu_busy(gpu, plan1080, args.busy_frames)
    print(f"surgery 1920x1080, {args.busy_frames} frames: wall {busy['wall_ms']:.3f} ms/frame, GPU span "
          f"{busy['span_ms']:.3f} ms, GPU pass sum {busy['sum_ms']:.3f} ms, submit CPU {busy['cpu_submit_ms']:.3f} ms")
    print(f"GPU busy fraction: span/wall {100 * busy['span_fraction']:.1f}%, sum/wall "
          f"{100 * busy['sum_fraction']:.1f}% (target >= 95%)")


if __name__ == "__main__":
    main()
