"""Multi-device frame time (issue 16, docs/multi-gpu.md): one device vs splits over ``--devices``.

Graphs: ``surgery``, ``probe`` (tests/multi_graphs/probe_split.yaml) and the study's two
workloads (``benchmarks/multi_gpu_work``): ``pixels``, a per-pixel-heavy full-screen pass
(``--iterations`` per pixel; sort-first), and ``mesh``, a procedural mesh of ``--triangles``
triangles (sort-last; the study used >= 100M). For each graph every configuration is loaded
once: one device, then each split x transfer (``shared``: VK_EXT_external_memory_host, one
host allocation imported by both devices; ``staged``: readback + staging) x pipelining, and
for sort-first one ``--balances dynamic`` configuration (``DynamicBalance``: bands in 8-row
steps from measured times; ``plan_loads`` in the JSON counts its layouts).
Measurement (``benchmarks/multi_gpu_work/measure.py``): a warm-up of ``--warmup-s`` seconds
per configuration, then ``--rounds`` rounds alternating configurations, each round
``--frames`` serial frames (fenced ``run(1)``: GPU span per device, host wall) and one stream
of ``--frames`` frames (``run(k)``: wall per frame as the runtime overlaps frames). Every
configuration gets the same frame counts and method.

Columns: gpu ms per device (median serial span; each span checked to cover all of its
device's passes and to lie inside the host interval that waited for it: ``check``), critical
(device 0 + slowest sender; pipelined: the larger of the two), serial and stream wall ms per
frame, copy (host ms moving tiles: 0 when shared), composite (device 0's upload/composite
passes), speedup = one-device stream wall / stream wall, eff. = speedup / devices, gpu x =
one-device span / critical. Two logical devices on one GPU (``--devices 0,0``) share that GPU:
these figures measure the machinery's overhead, and efficiency above 1/devices is not expected.

    python3 -m benchmarks.multi_gpu --devices 0,0 [--size 640x360] [--frames 5] [--rounds 3]
        [--warmup-s 0.3] [--graphs surgery,probe,pixels,mesh] [--splits sort-first,sort-last]
        [--transfers shared,staged] [--pipelined off,on] [--balances static,dynamic] [--triangles 100000000]
        [--iterations 4096] [--validate] [--out-json P]
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

from benchmarks import multi_gpu_work as work  # noqa: E402 -- registers the workloads' passes
from benchmarks.multi_gpu_work.measure import Config  # noqa: E402

GRAPHS = {"surgery": "surgery", "probe": str(ROOT / "tests" / "multi_graphs" / "probe_split.yaml"),
          "pixels": str(work.PIXELS), "mesh": str(work.MESH)}
#: the splits that make sense per workload when --splits is not given
SPLITS = {"pixels": ("sort-first",), "mesh": ("sort-last", "sort-first")}


def _configs(gpus: list[Any], name: str, args: argparse.Namespace, size: tuple[int, int]) -> list[Config]:
    from rgraph.compiler.multi_device import Split
    from rgraph.compiler.pipeline import compile_graph, compile_graph_plan
    from rgraph.vk.multi.run import MultiExecutable, host_import_supported

    graph = GRAPHS.get(name, name)
    params = {"pixels": {"mg.iterations": str(args.iterations)},
              "mesh": {"mg.triangles": str(args.triangles), "mg.chunks": str(args.chunks)}}.get(name, {})
    memory = gpus[0].memory_requirements()
    one = compile_graph(graph, size=size, memory=memory, params=params)
    configs = [Config(name, None, None, False, gpus[0].load(one), one)]
    shared_ok = all(host_import_supported(g) for g in gpus)
    splits = args.splits.split(",") if args.splits else SPLITS.get(name, ("sort-first", "sort-last"))
    for mode in splits:
        plan = compile_graph_plan(graph, size=size, memory=memory, params=params, split=Split(len(gpus), mode))
        for transfer in args.transfers.split(","):
            if transfer == "shared" and not shared_ok:
                print(f"multi_gpu: {name} {mode}: no VK_EXT_external_memory_host, shared skipped", file=sys.stderr)
                continue
            for pipe in args.pipelined.split(","):
                try:
                    multi = MultiExecutable(gpus, plan, transfer=transfer, pipelined=pipe == "on")
                except Exception as exc:  # noqa: BLE001 -- one configuration refused: the others still run
                    print(f"multi_gpu: {name} {mode} {transfer}: skipped ({exc})", file=sys.stderr)
                    continue
                if multi.shared_error:
                    print(f"multi_gpu: {name} {mode}: shared allocation refused ({multi.shared_error})", file=sys.stderr)
                configs.append(Config(name, mode, transfer, pipe == "on", multi, plan))
        if mode == "sort-first" and "dynamic" in args.balances.split(","):
            from rgraph.vk.multi.balance import DynamicBalance

            transfer = "shared" if shared_ok and "shared" in args.transfers else "staged"
            balance = DynamicBalance(gpus, lambda w, mode=mode: compile_graph_plan(
                graph, size=size, memory=memory, params=params, split=Split(len(gpus), mode, "dynamic", w)),
                transfer=transfer)
            configs.append(Config(name, mode, transfer, False, balance, plan, balance="dynamic"))
    return configs


def measure(gpus: list[Any], name: str, args: argparse.Namespace, size: tuple[int, int]) -> list[dict[str, Any]]:
    configs = _configs(gpus, name, args, size)
    try:
        for c in configs:
            c.warm(args.warmup_s)
        for _ in range(args.rounds):
            for c in configs:
                for _ in range(args.frames):
                    c.serial_frame()
                c.stream(args.frames)
        rows = [c.row() for c in configs]
    finally:
        for c in configs:
            c.close()
    base = rows[0]
    for r in rows:
        r["speedup"] = base["stream_wall_ms"] / r["stream_wall_ms"] if r["stream_wall_ms"] else 0.0
        r["efficiency"] = r["speedup"] / len(r["gpu_ms"])
        r["gpu_speedup"] = base["critical_ms"] / r["critical_ms"] if r["critical_ms"] else 0.0
    return rows


def table(rows: list[dict[str, Any]]) -> list[str]:
    out = [f"{'graph':8} {'config':26} {'gpu ms per device':>18} {'critical':>9} {'serial':>8} {'stream':>8} "
           f"{'copy':>7} {'compos.':>8} {'speedup':>8} {'eff.':>5} {'gpu x':>6}  check  cut"]
    for r in rows:
        out.append(f"{r['graph']:8} {r['config']:26} {'/'.join(f'{x:.2f}' for x in r['gpu_ms']):>18} "
                   f"{r['critical_ms']:9.2f} {r['serial_wall_ms']:8.2f} {r['stream_wall_ms']:8.2f} "
                   f"{r['copy_ms']:7.2f} {r['composite_ms']:8.3f} {r['speedup']:8.2f} {r['efficiency']:5.2f} "
                   f"{r['gpu_speedup']:6.2f}  {'ok' if not r['findings'] else len(r['findings']):5}  "
                   f"{r['cut'] or ''}")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--devices", default="0,0")
    parser.add_argument("--size", default="640x360")
    parser.add_argument("--frames", type=int, default=5, help="serial frames and stream frames per round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--warmup-s", type=float, default=0.3)
    parser.add_argument("--graphs", default="surgery,probe,pixels,mesh")
    parser.add_argument("--splits", default=None, help="default: per graph (pixels sort-first, mesh both)")
    parser.add_argument("--transfers", default="shared,staged")
    parser.add_argument("--pipelined", default="off,on")
    parser.add_argument("--balances", default="static,dynamic",
                        help="dynamic: one more sort-first configuration, not pipelined, bands from measured times")
    parser.add_argument("--triangles", type=int, default=100_000_000)
    parser.add_argument("--chunks", type=int, default=64)
    parser.add_argument("--iterations", type=int, default=4096)
    parser.add_argument("--validate", action="store_true")
    parser.add_argument("--out-json", type=Path)
    args = parser.parse_args(argv)
    from rgraph.api import open_device
    from rgraph.commands.common import parse_size

    indices = [int(x) for x in args.devices.split(",")]
    size = parse_size(args.size)
    gpus = [open_device(validate=args.validate, device=i, verbose=False) for i in indices]
    rows: list[dict[str, Any]] = []
    try:
        for name in args.graphs.split(","):
            rows += measure(gpus, name, args, size)
    finally:
        messages = [m for g in gpus for m in g.close()]
    findings = [f for r in rows for f in r["findings"]]
    print(f"devices {indices} ({gpus[0].name}), size {size[0]}x{size[1]}, warm-up >= {args.warmup_s} s, "
          f"{args.rounds} rounds x ({args.frames} serial + {args.frames} stream frames), mesh "
          f"{work.mesh_triangles(args.triangles, args.chunks)} triangles, pixels {args.iterations} iterations, "
          f"validation messages: {len(messages) if args.validate else 'off'}, span findings: {len(findings)}")
    print("\n".join(table(rows)))
    for f in findings:
        print(f"span: {f}")
    if args.out_json:
        args.out_json.write_text(json.dumps({"devices": indices, "device": gpus[0].name, "size": list(size),
                                             "argv": sys.argv[1:] if argv is None else argv, "rows": rows,
                                             "messages": len(messages)}, indent=1) + "\n")
    return 1 if (args.validate and messages) or findings else 0


if __name__ == "__main__":
    raise SystemExit(main())
