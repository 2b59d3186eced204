"""Multi-device frame time (issue 16, docs/multi-gpu.md): one device vs a split over ``--devices``.

For each graph: the one-device plan (``rgraph.open_device`` on the first index) and, for each
split, the multi-device plan on one logical device per ``--devices`` entry
(``rgraph.vk.multi.run.MultiExecutable``). Figures per configuration (medians over
``--frames``):

- gpu ms per device: the executor's GPU time of that device's frame (timestamp queries);
- critical ms: max over senders of their GPU ms + device 0's GPU ms (the GPU path of a frame
  when device 0 waits for the tiles, as this runtime orders it);
- copy ms: host time reading the tile buffers back (device -> host, staged);
- composite ms: device 0's GPU time of the upload / composite passes;
- host frame ms: wall time of a whole frame (device 0's executable is re-loaded per frame in
  this version, so this is dominated by loading; see docs/multi-gpu.md);
- speedup = one-device GPU ms / critical ms, efficiency = speedup / devices.

    python3 -m benchmarks.multi_gpu --devices 0,0 [--size 640x360] [--frames 3] [--graphs surgery,probe]
        [--splits sort-first,sort-last] [--validate] [--out-json P]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

GRAPHS = {"surgery": "surgery", "probe": str(ROOT / "tests" / "multi_graphs" / "probe_split.yaml")}


def _one_device(gpu: Any, graph: str, size: tuple[int, int], frames: int) -> dict[str, Any]:
    from rgraph.compiler.pipeline import compile_graph

    plan = compile_graph(graph, size=size, memory=gpu.memory_requirements())
    with gpu.load(plan) as exe:
        exe.run(1)  # warm-up
        summary = exe.run(frames)
    return {"gpu_ms": summary.timings.get("total_ms") or 0.0}


def _split(gpus: list[Any], graph: str, size: tuple[int, int], frames: int, mode: str) -> dict[str, Any]:
    from rgraph.compiler.multi_device import Split
    from rgraph.compiler.pipeline import compile_graph_plan
    from rgraph.vk.multi.run import MultiExecutable

    plan = compile_graph_plan(graph, size=size, memory=gpus[0].memory_requirements(), split=Split(len(gpus), mode))
    multi = MultiExecutable(gpus, plan)
    try:
        multi.run(1)  # warm-up
        s = multi.run(frames)
    finally:
        multi.close()
    composite = sum(ms for name, ms in s.device_passes[0].items() if ".upload" in name or name.startswith("composite"))
    critical = max(s.device_ms[1:], default=0.0) + s.device_ms[0]
    return {"gpu_ms": s.device_ms, "critical_ms": critical, "copy_ms": s.readback_ms, "composite_ms": composite,
            "host_frame_ms": s.frame_ms, "host_memory_import": s.host_memory_import,
            "cut": plan.multi_device["cut"], "crossing": list(plan.multi_device["crossing"])}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--devices", default="0,0")
    parser.add_argument("--size", default="640x360")
    parser.add_argument("--frames", type=int, default=3)
    parser.add_argument("--graphs", default="surgery,probe")
    parser.add_argument("--splits", default="sort-first,sort-last")
    parser.add_argument("--validate", action="store_true")
    parser.add_argument("--out-json", type=Path)
    args = parser.parse_args(argv)
    from rgraph.api import open_device
    from rgraph.commands.common import parse_size

    indices = [int(x) for x in args.devices.split(",")]
    size = parse_size(args.size)
    gpus = [open_device(validate=args.validate, device=i, verbose=False) for i in indices]
    rows = []
    try:
        for name in args.graphs.split(","):
            one = _one_device(gpus[0], GRAPHS.get(name, name), size, args.frames)
            rows.append({"graph": name, "split": "one device", **one})
            for mode in args.splits.split(","):
                r = _split(gpus, GRAPHS.get(name, name), size, args.frames, mode)
                speedup = one["gpu_ms"] / r["critical_ms"] if r["critical_ms"] else 0.0
                rows.append({"graph": name, "split": mode, **r, "speedup": speedup,
                             "efficiency": speedup / len(gpus)})
    finally:
        messages = [m for g in gpus for m in g.close()]
    print(f"devices {indices} ({gpus[0].name}), size {size[0]}x{size[1]}, {args.frames} frames, "
          f"validation messages: {len(messages) if args.validate else 'off'}")
    print(f"{'graph':8} {'split':11} {'gpu ms per device':>24} {'critical':>9} {'copy':>7} {'compos.':>8} "
          f"{'host fr.':>9} {'speedup':>8} {'eff.':>6}  cut")
    for r in rows:
        gpu = r["gpu_ms"] if isinstance(r["gpu_ms"], list) else [r["gpu_ms"]]
        print(f"{r['graph']:8} {r['split']:11} {'/'.join(f'{x:.2f}' for x in gpu):>24} "
              f"{r.get('critical_ms', gpu[0]):9.2f} {r.get('copy_ms', 0):7.2f} {r.get('composite_ms', 0):8.3f} "
              f"{r.get('host_frame_ms', 0):9.1f} {r.get('speedup', 1):8.2f} {r.get('efficiency', 1):6.2f}  "
              f"{r.get('cut', '')}")
    if args.out_json:
        args.out_json.write_text(json.dumps({"devices": indices, "size": list(size), "rows": rows}, indent=1) + "\n")
    return 1 if args.validate and messages else 0


if __name__ == "__main__":
    raise SystemExit(main())
