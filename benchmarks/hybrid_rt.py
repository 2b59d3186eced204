"""Hybrid rendering vs stand-alone ray tracing: the study's Table 3 per scene and camera.

    python3 -m benchmarks.hybrid_rt                       # 1280x720, 3 scenes x 5 cameras, 50 frames
    python3 -m benchmarks.hybrid_rt --size small          # 64x36, 2 frames: lavapipe smoke run
    python3 -m benchmarks.hybrid_rt --depth-sweep         # rt.max_depth 1..8 vs a depth-16 reference

Per scene and camera: stand-alone frame T (graphs/rt_standalone.yaml, the GPU span of the frame);
the hybrid frame t (its GPU span), split at the end of the raster visibility buffer: t_b = frame
start -> G-buffer end (the sky pass, tiny and independent of it, included), t_a = G-buffer end ->
frame end (ray reset/classification, shading with shadow rays, indirect secondary rays); t_a / T,
t / T; all medians of GPU timestamps over ``--frames`` frames. (Each pass's own timestamp pair
starts at TOP_OF_PIPE before its barriers, so it overlaps the previous pass still draining:
summing per-pass times double-counts; the per-pass medians are kept in the JSON as ``passes``.)
Image agreement hybrid vs stand-alone:
PSNR and SSIM of the tone-clamped [0, 1] images, FLIP (LDR) when flip-evaluator is installed;
the share of pixels that traced secondary rays (the compacted list's length / pixels).
Output: a Markdown table on stdout and JSON lines (``--json``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("rt_living_room", "rt_conference", "rt_gallery")
SIZES = {"full": (1280, 720), "small": (64, 36)}
GBUFFER_PASSES = ("gbuffer",)


def _run(graph: str, scene: Path, camera: int, size: tuple[int, int], frames: int, params: dict[str, str],
         extra: tuple[str, ...] = ()) -> tuple[dict, dict[str, Any]]:
    from rgraph.api import open_device
    from rgraph.compiler.pipeline import compile_graph

    with open_device(validate=False, verbose=False) as gpu:  # one device sizes and runs the plan
        plan = compile_graph(graph, scene_path=scene, size=size, camera=camera, params=params,
                             extra_outputs=list(extra), memory=gpu.memory_requirements())
        result = gpu.load(plan).run_and_check(frames, check_data=False, read_outputs=True)
    return result.timings, result.outputs


def _metrics(reference: np.ndarray, test: np.ndarray) -> dict[str, float | None]:
    from rgraph.sweep import flip
    from rgraph.sweep.metrics import psnr, ssim

    a, b = np.clip(reference, 0.0, 1.0), np.clip(test, 0.0, 1.0)
    gray_a, gray_b = a.mean(axis=-1), b.mean(axis=-1)
    f = flip.flip_ldr(a.astype(np.float32), b.astype(np.float32))
    return {"psnr_db": psnr(a, b), "ssim": ssim(gray_a, gray_b), "flip": None if f is None else float(f[1])}


def measure(scene: str, camera: int, size: tuple[int, int], frames: int, depth: int) -> dict[str, Any]:
    path = ROOT / "graphs" / "scenes" / f"{scene}.yaml"
    params = {"rt.max_depth": str(depth)}
    t_alone, alone = _run("rt_standalone", path, camera, size, frames, params)
    t_hybrid, hybrid = _run("rt_hybrid", path, camera, size, frames, params, extra=("ray_args", "visibility"))
    T = t_alone["total_ms"]
    t = t_hybrid["total_ms"]
    t_b = max(t_hybrid["intervals"][name]["end_ms"] for name in GBUFFER_PASSES)
    t_a = t - t_b
    traced = int(np.frombuffer(hybrid["ray_args"].tobytes()[:4], dtype=np.uint32)[0]) if "ray_args" in hybrid else 0
    row = {"scene": scene, "camera": camera, "size": list(size), "frames": frames, "max_depth": depth,
           "T_ms": T, "t_a_ms": t_a, "t_a_over_T": t_a / T, "t_b_ms": t_b, "t_ms": t, "t_over_T": t / T,
           "passes": t_hybrid["passes"],
           "traced_share": traced / (size[0] * size[1]),
           "boundary_share": boundary_share(hybrid["visibility"][..., 0], prim_bits_of(path, size, camera)),
           **_metrics(alone["color"][..., :3].astype(np.float64), hybrid["color"][..., :3].astype(np.float64))}
    return row


def prim_bits_of(path: Path, size: tuple[int, int], camera: int) -> int:
    from rgraph.passes.raytrace_hybrid import prim_bits

    from rgraph.scene.build import load_scene_data

    return prim_bits(load_scene_data(path, size, camera))


def boundary_share(ids: np.ndarray, bits: int) -> float:
    """Share of pixels whose camera ray the hybrid traces because they border another instance
    or the sky (shaders/rt/hybrid.glsl: on_boundary; pixels whose centre misses the rasterized
    triangle, also traced, are not counted)."""
    from rgraph.passes.raytrace_hybrid import decode_visibility

    inst, _prim = decode_visibility(ids, bits)
    padded = np.pad(inst, 1, mode="edge")
    differs = np.zeros(inst.shape, dtype=bool)
    for dy, dx in ((0, 1), (2, 1), (1, 0), (1, 2)):
        differs |= padded[dy:dy + inst.shape[0], dx:dx + inst.shape[1]] != inst
    return float(differs.mean())


def depth_sweep(scene: str, camera: int, size: tuple[int, int], frames: int) -> list[dict[str, Any]]:
    """Stand-alone and hybrid at rt.max_depth 1..8 against the stand-alone depth-16 image."""
    path = ROOT / "graphs" / "scenes" / f"{scene}.yaml"
    _t, ref = _run("rt_standalone", path, camera, size, 1, {"rt.max_depth": "16"})
    reference = ref["color"][..., :3].astype(np.float64)
    rows = []
    for depth in range(1, 9):
        for graph in ("rt_standalone", "rt_hybrid"):
            timings, out = _run(graph, path, camera, size, frames, {"rt.max_depth": str(depth)})
            rows.append({"scene": scene, "camera": camera, "graph": graph, "max_depth": depth,
                         "frame_ms": timings["total_ms"], **_metrics(reference, out["color"][..., :3].astype(np.float64))})
    return rows


def _fmt(x: Any, spec: str) -> str:
    return "-" if x is None else format(x, spec)


def table(rows: list[dict[str, Any]]) -> str:
    head = ("| scene | camera | T (ms) | t_a (ms) | t_a/T | t_b (ms) | t (ms) | t/T | PSNR (dB) | SSIM | FLIP "
            "| traced | primary traced |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    lines = [head]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['camera']} | {r['T_ms']:.3f} | {r['t_a_ms']:.3f} | {r['t_a_over_T']:.2f} "
                     f"| {r['t_b_ms']:.3f} | {r['t_ms']:.3f} | {r['t_over_T']:.2f} | {_fmt(r['psnr_db'], '.1f')} "
                     f"| {_fmt(r['ssim'], '.4f')} | {_fmt(r['flip'], '.4f')} | {r['traced_share']:.1%} "
                     f"| {r['boundary_share']:.1%} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", default="full", help="full (1280x720), small (64x36) or WxH")
    parser.add_argument("--frames", type=int, default=None, help="frames per run (default 50; small: 2)")
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--cameras", default="0,1,2,3,4")
    parser.add_argument("--max-depth", type=int, default=4)
    parser.add_argument("--depth-sweep", action="store_true", help="rt.max_depth 1..8 vs depth 16 (camera 0)")
    parser.add_argument("--json", type=Path, help="also write JSON lines here")
    args = parser.parse_args(argv)
    size = SIZES.get(args.size) or tuple(int(v) for v in args.size.lower().split("x"))
    frames = args.frames or (2 if args.size == "small" else 50)
    scenes = [s for s in args.scenes.split(",") if s]
    rows: list[dict[str, Any]] = []
    for scene in scenes:
        if args.depth_sweep:
            rows += depth_sweep(scene, int(args.cameras.split(",")[0]), size, frames)
            continue
        for camera in (int(c) for c in args.cameras.split(",") if c):
            rows.append(measure(scene, camera, size, frames, args.max_depth))
            print(json.dumps(rows[-1]), file=sys.stderr)
    if args.json:
        args.json.write_text("".join(json.dumps(r) + "\n" for r in rows))
    if args.depth_sweep:
        print("| scene | graph | max_depth | frame (ms) | PSNR vs depth 16 (dB) | SSIM |\n|---|---|---:|---:|---:|---:|")
        for r in rows:
            print(f"| {r['scene']} | {r['graph']} | {r['max_depth']} | {r['frame_ms']:.3f} | "
                  f"{_fmt(r['psnr_db'], '.1f')} | {_fmt(r['ssim'], '.4f')} |")
    else:
        print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
