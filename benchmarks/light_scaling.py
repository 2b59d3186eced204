"""Clustered vs all-lights GPU time over light counts, and the lighting test (issue 17).

For each light count N (default 16, 64, 256, 1,024, 4,096, 16,384) the lighting-test geometry
(968 instanced boxes on a floor, graphs/scenes/lighting_test.yaml) gets N seeded point lights
(the FORMAT.md 7 generator: bounds of many_lights.yaml, radius [1.5, 4] m, so the light
density grows with N) and graphs/clustered.yaml runs it three ways: ``lighting.mode=all_lights``
(the reference: every fragment shades every light), clustered with index lists and clustered
with bitmasks (``clusters.list``). Reported per run: the median GPU ms of every pass
(timestamps) and of the frame (first pass start to last pass end), the light-list statistics,
and the largest difference of the tonemapped image from all_lights in 8-bit sRGB codes.

Then the lighting test itself (lighting_test.yaml, 25 lights, clustered): frame wall time,
FPS and GPU busy fraction over pipelined frames, measured as benchmarks/frame_cpu.py does
(GPU span / wall and summed pass time / wall; GPU devices only).

    python3 -m benchmarks.light_scaling [--size 1920x1080] [--counts 16,64,...] [--frames 30]
        [--busy-frames 300] [--json OUT.json]
    lavapipe:  python3 -m benchmarks.light_scaling --size 160x90 --counts 16,64,256 --frames 2 --busy-frames 0
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from rgraph.resources import builtin_passes

builtin_passes()  # rgraph.passes also from a plain checkout on PYTHONPATH (the GPU machines)
ROOT = Path(__file__).resolve().parent.parent
GRAPH = ROOT / "graphs" / "clustered.yaml"
SCENES = ROOT / "graphs" / "scenes"
COUNTS = (16, 64, 256, 1024, 4096, 16384)
RUNS = {"all_lights": {"lighting.mode": "all_lights"},
        "clustered": {"lighting.mode": "clustered", "clusters.list": "indices"},
        "bitmask": {"lighting.mode": "clustered", "clusters.list": "bitmask"}}
STAGES = ("light_setup", "cluster_build", "depth_prepass", "light_assign", "forward", "heatmap", "tonemap")


def scene_with_lights(count: int, folder: Path) -> Path:
    """lighting_test.yaml's camera and geometry with ``count`` generated lights."""
    text = (SCENES / "lighting_test.yaml").read_text()
    head, _, rest = text.partition("lights:\n")
    _, _, tail = rest.partition("materials:\n")
    lights = (f"  - {{generate: point, count: {count}, seed: 2, bounds: [[-40, 0.5, -20], [40, 4.0, 20]], "
              f"radius: [1.5, 4], intensity: [2, 8]}}\n")
    path = folder / f"lights_{count}.yaml"
    path.write_text(f"{head}lights:\n{lights}materials:\n{tail}".replace("name: lighting_test", f"name: lights_{count}"))
    return path


def run_once(gpu: Any, scene: Path, size: tuple[int, int], params: dict[str, str], frames: int) -> dict[str, Any]:
    from rgraph.passes.cluster_report import stats_of
    from rgraph.passes.tonemap_ref import srgb_codes

    from rgraph.compiler.pipeline import compile_graph

    plan = compile_graph(GRAPH, scene_path=scene, size=size, params=params, memory=gpu.memory_requirements())
    result = gpu.load(plan).run_and_check(frames, check_data=False, read_outputs=True)
    t = result.timings
    return {"device": result.device_name, "frame_ms": t.get("total_ms"),
            "passes_ms": {k: v for k, v in t["passes"].items()}, "stats": stats_of(result.outputs["cluster_stats"]),
            "codes": srgb_codes(result.outputs["color"][..., :3])}


def scaling(gpu: Any, size: tuple[int, int], counts: list[int], frames: int, max_indices: int) -> list[dict[str, Any]]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in counts:
            scene = scene_with_lights(n, Path(tmp))
            runs = {name: run_once(gpu, scene, size, {**p, "clusters.max_indices": str(max_indices)}, frames)
                    for name, p in RUNS.items()}
            ref = runs["all_lights"]["codes"]
            row: dict[str, Any] = {"lights": n, "device": runs["all_lights"]["device"]}
            for name, r in runs.items():
                row[name] = {"frame_ms": r["frame_ms"], "passes_ms": r["passes_ms"], "stats": r["stats"],
                             "max_code_diff": int(np.abs(r["codes"] - ref).max()),
                             "pixels_differing": int(np.count_nonzero(np.any(r["codes"] != ref, axis=-1)))}
            rows.append(row)
            print(_line(row), flush=True)
    return rows


def _ms(v: float | None) -> str:
    return "-" if v is None else f"{v:.3f}"


def _line(row: dict[str, Any]) -> str:
    a, c, b = row["all_lights"], row["clustered"], row["bitmask"]
    speed = (a["frame_ms"] / c["frame_ms"]) if a["frame_ms"] and c["frame_ms"] else float("nan")
    return (f"{row['lights']:>6} lights: all_lights {_ms(a['frame_ms'])} ms (forward {_ms(a['passes_ms'].get('forward'))}) | "
            f"clustered {_ms(c['frame_ms'])} ms (assign {_ms(c['passes_ms'].get('light_assign'))}, forward "
            f"{_ms(c['passes_ms'].get('forward'))}; diff {c['max_code_diff']} codes; overflow "
            f"{c['stats']['overflowed_froxels']}) | bitmask {_ms(b['frame_ms'])} ms (assign "
            f"{_ms(b['passes_ms'].get('light_assign'))}, forward {_ms(b['passes_ms'].get('forward'))}; diff "
            f"{b['max_code_diff']}; overflow {b['stats']['overflowed_froxels']}) | speed-up {speed:.1f}x")


def table(rows: list[dict[str, Any]]) -> str:
    """Markdown: one line per light count and run, a column per stage."""
    head = "| lights | run | " + " | ".join(STAGES) + " | frame ms | max diff (codes) | overflowed froxels |"
    lines = [head, "|" + "---|" * (len(STAGES) + 5)]
    for row in rows:
        for name in RUNS:
            r = row[name]
            stages = " | ".join(_ms(r["passes_ms"].get(s)) for s in STAGES)
            lines.append(f"| {row['lights']} | {name} | {stages} | {_ms(r['frame_ms'])} | {r['max_code_diff']} | "
                         f"{r['stats']['overflowed_froxels']} |")
    return "\n".join(lines)


def lighting_test(gpu: Any, size: tuple[int, int], frames: int) -> dict[str, Any] | None:
    """Frame time, FPS and GPU busy of lighting_test.yaml (clustered), as frame_cpu.gpu_busy measures."""
    from benchmarks.frame_cpu import gpu_busy
    from rgraph.compiler.pipeline import compile_graph

    if gpu.choice["type"] == "cpu" or frames <= 0:
        return None
    plan = compile_graph(GRAPH, scene_path=SCENES / "lighting_test.yaml", size=size, memory=gpu.memory_requirements())
    busy = gpu_busy(gpu, plan, frames)
    return {**busy, "fps": 1000.0 / busy["wall_ms"]}


def main(argv: list[str] | None = None) -> int:
    from rgraph.resources import builtin_passes

    builtin_passes()  # rgraph.passes from a checkout without an install (the GPU machine)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="1920x1080")
    parser.add_argument("--counts", default=",".join(map(str, COUNTS)))
    parser.add_argument("--frames", type=int, default=30, help="frames per run (median GPU times)")
    parser.add_argument("--busy-frames", type=int, default=300, help="pipelined frames of the lighting test (0: skip)")
    parser.add_argument("--max-indices", type=int, default=1 << 24, help="clusters.max_indices (list capacity)")
    parser.add_argument("--json", type=Path, help="write every figure as JSON")
    args = parser.parse_args(argv)
    w, h = (int(x) for x in args.size.lower().split("x"))
    counts = [int(c) for c in args.counts.split(",") if c.strip()]
    import rgraph

    with rgraph.open_device(validate=False, verbose=False) as gpu:  # one device for every run
        rows = scaling(gpu, (w, h), counts, args.frames, args.max_indices)
        print(table(rows))
        busy = lighting_test(gpu, (w, h), args.busy_frames)
    if busy is None:
        print("lighting test GPU busy: skipped (CPU device, or --busy-frames 0)")
    else:
        print(f"lighting test {w}x{h} (25 lights, clustered), {args.busy_frames} frames: wall {busy['wall_ms']:.3f} "
              f"ms/frame = {busy['fps']:.0f} FPS; GPU span {busy['span_ms']:.3f} ms, pass sum {busy['sum_ms']:.3f} ms; "
              f"GPU busy span/wall {100 * busy['span_fraction']:.1f}%, sum/wall {100 * busy['sum_fraction']:.1f}%")
    if args.json:
        args.json.write_text(json.dumps({"size": [w, h], "rows": rows, "lighting_test": busy}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
