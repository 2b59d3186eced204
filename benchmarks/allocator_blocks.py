"""The allocator experiment (issue 4.7, docs/allocator.md): mesh vertex buffers in device-memory
blocks of 0 (one VkDeviceMemory per buffer), 4, 16, 64, 256 MiB; load time and frame time.

For each mix (rigid: every mesh device-local and uploaded once; deformable: every mesh
host-visible, one copy per frame in flight, rewritten each frame; mixed: the scene's own
deformable meshes, 10%) and each block size, compiles ``graphs/allocator_lines.yaml`` with
the ``alloc.*`` params and runs it on one device (``rgraph.open_device``; each run loads
its plan afresh, so its memory blocks are allocated and freed within the run). Figures come from the ``mesh_lines`` pass itself
(``MeshLines.last_report``: wall clock around the real Vulkan calls) and from the run's
timings (timestamp queries):

- allocs: live VkDeviceMemory objects for the meshes; MiB alloc / bound / used: memory
  allocated, bound to buffers (requirement sizes incl. the deformable growth room), and
  filled with vertices (internal fragmentation = 1 - bound / alloc);
- load ms: pool creation + buffer creation, allocation, binding, staging upload (copies,
  barrier, submit, fence wait) and the first fill of the dynamic buffers; vkAlloc ms: the
  part inside vkAllocateMemory; free ms: destroying the buffers and freeing the memory;
- frame ms: the executor's median CPU time per frame from the fence wait through the submit
  (so it includes waiting for the GPU two frames back); update ms: the pass's per-frame CPU
  work (NumPy wobble of the deformable meshes into mapped memory); GPU ms: the pass's median
  GPU time (timestamps).

    python benchmarks/allocator_blocks.py [--meshes N] [--segments S] [--frames F] [--device I]
        [--sizes 0,4,16,64,256] [--mix rigid,deformable,mixed] [--size WxH] [--validate]
        [--over-limit error|try] [--max-allocations N] [--dynamic-memory host|device_local]
        [--out-json P] [--plot P]
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
GRAPH = ROOT / "graphs" / "allocator_lines.yaml"
MIXES = {"rigid": 0.0, "deformable": 1.0, "mixed": -1.0}  # alloc.deformable_fraction (-1: the scene's)
MIB = 1 << 20


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--meshes", type=int, default=10_000, help="meshes (default 10000; 0 = the scene's)")
    ap.add_argument("--segments", type=int, default=100, help="line segments per mesh (default 100)")
    ap.add_argument("--frames", type=int, default=20, help="frames per run (default 20)")
    ap.add_argument("--device", type=int, default=None, help="Vulkan device index (default: rgraph's choice)")
    ap.add_argument("--sizes", default="0,4,16,64,256", help="block sizes in MiB, 0 = one allocation per buffer")
    ap.add_argument("--mix", default="rigid,deformable,mixed", help="any of rigid, deformable, mixed")
    ap.add_argument("--size", default="1280x720", help="output size WxH (default 1280x720)")
    ap.add_argument("--load-factor", type=float, default=1.5, help="deformable capacity / size (default 1.5)")
    ap.add_argument("--over-limit", choices=("error", "try"), default="error",
                    help="past maxMemoryAllocationCount: report (error) or let the driver decide (try)")
    ap.add_argument("--dynamic-memory", choices=("host", "device_local"), default="host",
                    help="deformable buffers in host memory or device-local host-visible memory (BAR)")
    ap.add_argument("--max-allocations", type=int, default=0, help="lower the allocation limit (0: the device's)")
    ap.add_argument("--validate", action="store_true", help="run under the validation layers (slower)")
    ap.add_argument("--out-json", type=Path, default=None, help="write rows and the command as JSON here")
    ap.add_argument("--plot", type=Path, default=None, help="draw load and frame time vs block size (PNG)")
    args = ap.parse_args(argv)
    args.sizes = [int(s) for s in args.sizes.split(",") if s.strip()]
    args.mix = [m.strip() for m in args.mix.split(",") if m.strip()]
    bad = [m for m in args.mix if m not in MIXES]
    if bad:
        ap.error(f"unknown --mix {bad}; choose from {', '.join(MIXES)}")
    w, _, h = args.size.partition("x")
    args.size = (int(w), int(h))
    return args


def compile_plan(args: argparse.Namespace, block_mib: int, mix: str, memory: Any) -> dict:
    """The graph compiled with this run's ``alloc.*`` params."""
    from rgraph.compiler.pipeline import compile_graph

    params = {"alloc.block_mib": str(block_mib), "alloc.meshes": str(args.meshes),
              "alloc.segments": str(args.segments), "alloc.deformable_fraction": str(MIXES[mix]),
              "alloc.load_factor": str(args.load_factor), "alloc.over_limit": args.over_limit,
              "alloc.max_allocations": str(args.max_allocations), "alloc.dynamic_memory": args.dynamic_memory}
    return compile_graph(GRAPH, params=params, size=args.size, memory=memory)


def run_one(gpu: Any, args: argparse.Namespace, plan: dict, block_mib: int, mix: str, frames: int) -> dict[str, Any]:
    from rgraph.impl import lookup
    from rgraph.vk.errors import ExecutionError

    cls: Any = lookup("mesh_lines")
    cls.last_report = {}
    t0 = time.perf_counter()
    row: dict[str, Any] = {"mix": mix, "block_mib": block_mib}
    try:
        result = gpu.load(plan).run_and_check(frames, check_data=False)
    except ExecutionError as exc:
        row.update(cls.last_report)
        row["error"] = str(exc)
        return row
    row.update(cls.last_report)
    row["run_s"] = time.perf_counter() - t0
    row["frame_ms"] = result.timings.get("cpu_submit_ms")
    row["gpu_ms"] = result.timings["passes"].get("lines")
    row["validation_messages"] = len(result.messages) if args.validate else None
    row["device"] = result.device_name
    return row


def fmt(value: Any, digits: int = 1) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


COLUMNS = [("mix", 10), ("block", 6), ("allocs", 7), ("MiB alloc", 10), ("MiB bound", 10), ("MiB used", 9),
           ("frag %", 7), ("load ms", 9), ("vkAlloc ms", 11), ("upload ms", 10), ("free ms", 8),
           ("frame ms", 9), ("update ms", 10), ("GPU ms", 8)]


def table(rows: list[dict[str, Any]]) -> str:
    head = " ".join(f"{name:>{w}}" for name, w in COLUMNS)
    lines = [head, "-" * len(head)]
    for r in rows:
        block = "dedic" if r["block_mib"] == 0 else f"{r['block_mib']}M"
        if "error" in r:
            need = r.get("allocations_needed")
            lines.append(f"{r['mix']:>10} {block:>6} {fmt(need):>7}  not run: {r['error']}")
            continue
        cells = [r["mix"], block, r["allocations"], r["allocated_bytes"] / MIB, r["bound_bytes"] / MIB,
                 r["used_bytes"] / MIB, 100 * r["internal_fragmentation"], r["load_ms"], r["vk_allocate_ms"],
                 r["upload_ms"], r.get("destroy_ms"), r["frame_ms"], r.get("update_ms"), r["gpu_ms"]]
        lines.append(" ".join(f"{fmt(c, 2 if name in ('frame ms', 'update ms', 'GPU ms') else 1):>{w}}"
                              for c, (name, w) in zip(cells, COLUMNS, strict=True)))
    return "\n".join(lines)


def plot(rows: list[dict[str, Any]], sizes: list[int], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_load, ax_frame) = plt.subplots(1, 2, figsize=(12, 4.5))
    xs = list(range(len(sizes)))
    labels = ["0 (one per\nbuffer)" if s == 0 else f"{s} MiB" for s in sizes]
    for mix in dict.fromkeys(r["mix"] for r in rows):
        ok = {r["block_mib"]: r for r in rows if r["mix"] == mix and "error" not in r}
        pts = [(x, ok[s]) for x, s in zip(xs, sizes, strict=True) if s in ok]
        if not pts:
            continue
        line = ax_load.plot([x for x, _ in pts], [r["load_ms"] for _, r in pts], "o-", label=f"{mix}: load")[0]
        ax_load.plot([x for x, _ in pts], [max(r["vk_allocate_ms"], 0.01) for _, r in pts], "x:",
                     color=line.get_color(), label=f"{mix}: in vkAllocateMemory")
        line = ax_frame.plot([x for x, _ in pts], [r["frame_ms"] for _, r in pts], "o-", label=f"{mix}: CPU frame")[0]
        ax_frame.plot([x for x, _ in pts], [r["gpu_ms"] for _, r in pts], "s--", color=line.get_color(),
                      label=f"{mix}: GPU pass")
        failed = [x for x, s in zip(xs, sizes, strict=True)
                  if any(r["mix"] == mix and r["block_mib"] == s and "error" in r for r in rows)]
        for x in failed:
            ax_load.annotate("over limit", (x, 0.95), xycoords=("data", "axes fraction"), ha="center",
                             color=line.get_color(), fontsize=8)
    ax_load.set_yscale("log")
    ax_frame.set_ylim(bottom=0)
    for ax, what in ((ax_load, "load time (ms, log scale)"), (ax_frame, "frame time (ms)")):
        ax.set_xticks(xs, labels)
        ax.set_xlabel("default block size")
        ax.set_ylabel(what)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def compile_all(gpu: Any, args: argparse.Namespace) -> tuple[dict[tuple[str, int], dict], dict, str, int]:
    """Every plan (and a tiny warm-up one), compiled with the image memory requirements of the
    device that will run them; the device's name and maxMemoryAllocationCount."""
    memory = gpu.memory_requirements()
    plans = {(mix, block): compile_plan(args, block, mix, memory) for mix in args.mix for block in args.sizes}
    warm = compile_plan(argparse.Namespace(**{**vars(args), "meshes": 16, "segments": 4}), 4, "mixed", memory)
    return plans, warm, gpu.name, int(gpu.device.properties.limits.maxMemoryAllocationCount)


def main(argv: list[str] | None = None) -> int:
    import rgraph

    args = parse_args(argv)
    with rgraph.open_device(validate=args.validate, device=args.device, verbose=False) as gpu:
        return measure(gpu, args, argv)


def measure(gpu: Any, args: argparse.Namespace, argv: list[str] | None) -> int:
    plans, warm, device_name, limit = compile_all(gpu, args)
    print(f"device: {device_name}; maxMemoryAllocationCount = {limit}; meshes {args.meshes} x "
          f"{args.segments} segments; {args.frames} frames at {args.size[0]}x{args.size[1]}"
          f"{'; validation on' if args.validate else ''}", flush=True)
    run_one(gpu, args, warm, 4, "mixed", 2)  # warm-up (SPIR-V cache, pipeline JIT, imports): not reported
    rows = []
    for (mix, block), plan in plans.items():
        row = run_one(gpu, args, plan, block, mix, args.frames)
        rows.append(row)
        state = row.get("error") or f"load {row['load_ms']:.0f} ms, frame {row['frame_ms']:.2f} ms"
        print(f"  {mix} block {block} MiB: {state}", file=sys.stderr, flush=True)
    print(table(rows))
    if args.out_json:
        args.out_json.parent.mkdir(parents=True, exist_ok=True)
        args.out_json.write_text(json.dumps({
            "command": " ".join([Path(sys.argv[0]).name, *(argv if argv is not None else sys.argv[1:])]),
            "device": device_name, "max_memory_allocation_count": limit, "host": platform.node(),
            "python": platform.python_version(), "meshes": args.meshes, "segments": args.segments,
            "frames": args.frames, "size": list(args.size), "rows": rows}, indent=1, sort_keys=True) + "\n")
    if args.plot:
        plot(rows, args.sizes, args.plot, f"{device_name}: {args.meshes} meshes x {args.segments} segments, "
                                         f"{args.frames} frames at {args.size[0]}x{args.size[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
