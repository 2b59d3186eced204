"""What synchronization costs: one graph, four plans, one process, rounds alternating.

- ``graph``: the compiler's plan (precise barriers, async compute, per-consumer semaphores);
- ``naive``: ``--sync naive`` (a full barrier before every pass, one queue, no semaphores);
- ``one_queue``: every pass moved to the graphics queue, then compiled normally (precise
  barriers, no overlap between queues);
- ``none``: ``one_queue`` with every barrier removed: the unsafe lower bound of one queue,
  for timing only (never run under validation; its results are undefined).

Per plan and round: wall milliseconds per frame over ``--frames`` pipelined frames (after
20 warm-up frames) and the GPU span (first pass start to last pass end, median). Prints
the median of the rounds and the ratios to ``graph``. ``--validate`` first runs ``graph``,
``naive`` and ``one_queue`` for two frames under validation and stops on any message.

    python -m benchmarks.barrier_cost [--graph async_overlap] [--size 1920x1080]
        [--frames 300] [--rounds 3] [-p NAME=VALUE ...] [--validate]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rgraph.compiler.naive_sync import naive_sync  # noqa: E402
from rgraph.compiler.pipeline import compile_plan, frontend  # noqa: E402
from rgraph.plan import to_json_dict  # noqa: E402
from rgraph.plan.model import Plan  # noqa: E402

MODES = ("graph", "naive", "one_queue", "none")
DEFAULT_GRAPH = Path(__file__).resolve().parents[1] / "graphs" / "async_overlap.yaml"


def no_barriers(plan: Plan) -> Plan:
    """``plan`` (one queue) with no barriers, releases or semaphores: unsafe, timing only."""
    if len(plan.queues) != 1:
        raise ValueError("no_barriers expects a one-queue plan (semaphores would be needed)")
    passes = tuple(replace(p, barriers=(), releases=(), waits=(), signals=()) for p in plan.passes)
    return replace(plan, passes=passes, stats=replace(plan.stats, sync="none", barriers=0, semaphores=0))


def plans(graph: str, size: tuple[int, int], params: dict[str, str], memory: Any) -> dict[str, dict]:
    spec = frontend(graph, params=params, size=size).spec
    normal = compile_plan(spec, memory_provider=memory)
    one_spec = replace(spec, passes=[replace(p, queue="graphics") for p in spec.passes])
    one = compile_plan(one_spec, memory_provider=memory)
    typed = {"graph": normal, "naive": naive_sync(normal), "one_queue": one, "none": no_barriers(one)}
    return {mode: to_json_dict(p) for mode, p in typed.items()}


def measure(plan: dict, frames: int) -> dict[str, float]:
    from rgraph.vk.executor import Executor

    executor = Executor(plan, validate=False, device_index=None, verbose=False)
    try:
        executor.run_frames(20)
        t0 = time.perf_counter()
        timings = executor.run_frames(frames)
        wall_ms = (time.perf_counter() - t0) * 1000.0 / frames
    finally:
        executor.close()
    return {"wall_ms": wall_ms, "span_ms": timings["total_ms"] or 0.0}


def validate(plan: dict, mode: str) -> None:
    from rgraph.vk.executor import execute_plan

    result = execute_plan(plan, validate=True, frames=2)
    if result.messages:
        raise SystemExit(f"{mode}: {len(result.messages)} validation message(s), first: {result.messages[0].text}")
    print(f"  {mode}: 0 validation messages")


def table(results: dict[str, list[dict[str, float]]]) -> str:
    wall = {m: statistics.median(r["wall_ms"] for r in v) for m, v in results.items()}
    span = {m: statistics.median(r["span_ms"] for r in v) for m, v in results.items()}
    lines = ["| plan | wall ms/frame | GPU span ms | wall / graph | span / graph |", "|---|---|---|---|---|"]
    for m in MODES:
        lines.append(f"| {m} | {wall[m]:.3f} | {span[m]:.3f} | {wall[m] / wall['graph']:.3f} | "
                     f"{span[m] / span['graph']:.3f} |")
    lines.append("")
    lines.append(f"graph / none (cost of precise sync over the one-queue bound): wall {wall['graph'] / wall['none']:.3f}; "
                 f"async overlap (graph / one_queue): wall {wall['graph'] / wall['one_queue']:.3f}; "
                 f"naive / graph: wall {wall['naive'] / wall['graph']:.3f}")
    return "\n".join(lines)


def parse_size(text: str) -> tuple[int, int]:
    w, h = text.lower().split("x")
    return int(w), int(h)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--graph", default=str(DEFAULT_GRAPH))
    parser.add_argument("--size", default="1920x1080", type=parse_size)
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("-p", "--param", action="append", default=[], metavar="NAME=VALUE")
    parser.add_argument("--validate", action="store_true", help="run graph, naive and one_queue under validation first")
    args = parser.parse_args(argv)
    params = dict(p.split("=", 1) for p in args.param)
    from rgraph.vk.memreq import live_requirements

    with live_requirements() as (memory, device):
        built = plans(args.graph, args.size, params, memory)
        name = device.name
    print(f"device: {name}; {Path(args.graph).stem} {args.size[0]}x{args.size[1]}, {args.frames} frames x {args.rounds} rounds")
    for m in MODES:
        st = built[m]["stats"]
        print(f"  {m:9s}: {len(built[m]['passes'])} passes, queues {built[m]['queues']}, {st['barriers']} barriers, "
              f"{st['semaphores']} semaphores")
    if args.validate:
        for m in ("graph", "naive", "one_queue"):
            validate(built[m], m)
    results: dict[str, list[dict[str, float]]] = {m: [] for m in MODES}
    for r in range(args.rounds):
        for m in MODES if r % 2 == 0 else tuple(reversed(MODES)):
            got = measure(built[m], args.frames)
            results[m].append(got)
            print(f"  round {r} {m:9s}: wall {got['wall_ms']:.3f} ms/frame, GPU span {got['span_ms']:.3f} ms", flush=True)
    print()
    print(table(results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
