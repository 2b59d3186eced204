"""Hybrid rendering vs stand-alone ray tracing: the study's Table 3 per scene and camera.

    python3 -m benchmarks.hybrid_rt                       # 1280x720, 3 scenes x 5 cameras, 50 frames
    python3 -m benchmarks.hybrid_rt --size small          # 64x36, 2 frames: lavapipe smoke run
    python3 -m benchmarks.hybrid_rt --depth-sweep         # rt.max_depth 1..8 vs a depth-16 reference

Fairness: per scene and camera every plan (stand-alone, hybrid, hardware-raster hybrid) is
loaded on one device, each runs untimed frames for ``--warmup`` seconds (the GPU clocks ramp up),
then the timed frames run in alternating chunks (``--chunk`` frames of each in turn, the order
rotating), so a clock change hits every plan alike; medians over the chunks' medians.

Per scene and camera: stand-alone frame T (graphs/rt_standalone.yaml, the GPU span of the frame);
the hybrid frame t (graphs/rt_hybrid.yaml: compute visibility buffer; its GPU span), split at
the end of the visibility buffer: t_b = frame start -> visibility buffer end (the sky pass, tiny
and independent of it, included), t_a = the rest (``shade``: every pixel's first surface with
shadow rays, tree level 0; ``wave_1`` .. ``wave_3``: one indirect trace per tree level over its
compacted ray list; ``resolve``); the ``raster`` columns are the same for
graphs/rt_hybrid_raster.yaml (hardware-raster visibility buffer, the older classify + per-pixel
walk design; ``--no-raster`` skips it); t_a / T,
t / T; all medians of GPU timestamps over ``--frames`` frames. (Each pass's own timestamp pair
starts at TOP_OF_PIPE before its barriers, so it overlaps the previous pass still draining:
summing per-pass times double-counts; the per-pass medians are kept in the JSON as ``passes``.)
Image agreement hybrid vs stand-alone:
PSNR and SSIM of the tone-clamped [0, 1] images, FLIP (LDR) when flip-evaluator is installed;
the share of pixels that traced secondary rays (the pixel list's length / pixels) and the rays of
each wavefront level (``level_rays``; ``level_overflow``: a list was full and its rays walked
in-thread, correct but slower). ``--first`` adds benchmarks/graphs/rt_hybrid_first.yaml in the same
alternation (``first`` columns; a compute pass shades every pixel that needs no ray and lists the
others, the shade pass traces only those; ``first listed``: the share it listed). ``--lean`` adds
benchmarks/graphs/rt_hybrid_lean.yaml (``lean`` columns: the bundled graph without the wavefront's
passes, which run empty every frame at the bundled ``rt.wavefront: 0``).
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
#: the visibility-buffer passes (t_b ends with the last of them): hardware raster or compute
GBUFFER_PASSES = ("gbuffer", "vis_clear", "vis_depth", "vis_depth_tiles", "vis_id", "vis_id_tiles")
RASTER_GRAPH = "rt_hybrid_raster"
WARMUP_S = 0.3  # seconds of frames of every plan before timing (GPU clocks ramp up); rgraph.api.WARMUP_S
CHUNK = 5       # frames per timed run; the plans alternate run by run
WAVE_LEVELS = 3  # the wavefront ray lists of graphs/rt_hybrid.yaml (rays_1 .. rays_3)
ASYNC_GRAPH = ROOT / "benchmarks" / "graphs" / "rt_hybrid_async.yaml"  # --async: matte pixels on the async queue
FIRST_GRAPH = ROOT / "benchmarks" / "graphs" / "rt_hybrid_first.yaml"  # --first: the compute shading pass
LEAN_GRAPH = ROOT / "benchmarks" / "graphs" / "rt_hybrid_lean.yaml"  # --lean: no wavefront passes
#: the hybrid variants' column groups in the table: (row key prefix, label)
VARIANTS = (("async_", "async"), ("traced_", "traced"), ("first_", "first"), ("lean_", "lean"))


def _run(graph: str, scene: Path, camera: int, size: tuple[int, int], frames: int, params: dict[str, str],
         extra: tuple[str, ...] = ()) -> tuple[dict, dict[str, Any]]:
    """One plan on its own device (the depth sweep: accuracy, not a timing comparison)."""
    from rgraph.api import open_device
    from rgraph.compiler.pipeline import compile_graph

    with open_device(validate=False, verbose=False) as gpu:  # one device sizes and runs the plan
        plan = compile_graph(graph, scene_path=scene, size=size, camera=camera, params=params,
                             extra_outputs=list(extra), memory=gpu.memory_requirements())
        result = gpu.load(plan).run_and_check(frames, check_data=False, read_outputs=True)
    return result.timings, result.outputs


def _median(values: list[float | None]) -> float | None:
    kept = [v for v in values if v is not None]
    return float(np.median(kept)) if kept else None


def _merge(chunks: list[dict[str, Any]]) -> dict[str, Any]:
    """Timings of several runs of one plan: the median of the runs' medians, per quantity."""
    passes = {name: _median([c["passes"].get(name) for c in chunks]) for name in chunks[0]["passes"]}
    ends = {name: _median([c["intervals"][name]["end_ms"] for c in chunks if name in c["intervals"]])
            for name in chunks[0].get("intervals", {})}
    return {"total_ms": _median([c["total_ms"] for c in chunks]), "passes": passes, "end_ms": ends,
            "frames": sum(c["frames"] for c in chunks)}


def side_by_side(gpu: Any, plans: dict[str, dict], frames: int, warmup_s: float, chunk: int) -> dict[str, Any]:
    """Load every plan on ``gpu``, run each for at least ``warmup_s`` seconds (alternating, so
    the clocks ramp up under all of them), then time ``frames`` frames of each in alternating
    chunks of ``chunk`` frames (a clock change hits every plan alike; the order rotates each
    round). Returns {name: {"timings": merged, "outputs": arrays}}."""
    import time

    exes = {name: gpu.load(plan) for name, plan in plans.items()}
    try:
        names = list(exes)
        start = time.perf_counter()
        while True:
            for name in names:
                exes[name].run(min(chunk, 2))
            if time.perf_counter() - start >= warmup_s:
                break
        chunks: dict[str, list] = {name: [] for name in names}
        sizes = [chunk] * (frames // chunk) + ([frames % chunk] if frames % chunk else [])
        for r, n in enumerate(sizes):
            for name in names[r % len(names):] + names[:r % len(names)]:
                chunks[name].append(exes[name].run(n).timings)
        return {name: {"timings": _merge(chunks[name]), "outputs": exes[name].read_outputs()} for name in names}
    finally:
        for exe in exes.values():
            exe.close()


def _metrics(reference: np.ndarray, test: np.ndarray) -> dict[str, float | None]:
    from rgraph.sweep import flip
    from rgraph.sweep.metrics import psnr, ssim

    a, b = np.clip(reference, 0.0, 1.0), np.clip(test, 0.0, 1.0)
    gray_a, gray_b = a.mean(axis=-1), b.mean(axis=-1)
    f = flip.flip_ldr(a.astype(np.float32), b.astype(np.float32))
    return {"psnr_db": psnr(a, b), "ssim": ssim(gray_a, gray_b), "flip": None if f is None else float(f[1])}


def _hybrid_columns(timings: dict[str, Any], T: float | None, outputs: dict[str, Any], alone: dict[str, Any],
                    prefix: str = "") -> dict[str, Any]:
    t = timings["total_ms"]
    t_b = max((v for k, v in timings["end_ms"].items() if k in GBUFFER_PASSES and v is not None), default=0.0)
    t_a = t - t_b
    m = _metrics(alone["color"][..., :3].astype(np.float64), outputs["color"][..., :3].astype(np.float64))
    return {f"{prefix}t_a_ms": t_a, f"{prefix}t_a_over_T": t_a / T, f"{prefix}t_b_ms": t_b, f"{prefix}t_ms": t,
            f"{prefix}t_over_T": t / T, f"{prefix}passes": timings["passes"],
            **({f"{prefix}{k}": v for k, v in m.items()})}


def measure(gpu: Any, scene: str, camera: int, size: tuple[int, int], frames: int, depth: int, *,
            warmup_s: float = WARMUP_S, chunk: int = CHUNK, raster: bool = True,
            hybrid_params: dict[str, str] | None = None, async_shade: bool = False,
            dump: Path | None = None, every_shadow_ray: bool = False, first: bool = False,
            lean: bool = False) -> dict[str, Any]:
    """One table row: stand-alone, the hybrid (compute visibility buffer; ``hybrid_params`` are
    its extra params) and, with ``raster``, the hybrid with the hardware-raster visibility buffer,
    side by side on ``gpu``; with ``async_shade`` also benchmarks/graphs/rt_hybrid_async.yaml
    (level 0 split, the matte pixels shaded on the async compute queue: ``async_`` columns);
    with ``every_shadow_ray`` also the hybrid with ``rt.light_maps: 0`` (every shadow ray traced: ``traced_``);
    with ``first`` also benchmarks/graphs/rt_hybrid_first.yaml (a compute pass shades the pixels that need
    no ray, the shade pass traces the listed rest: ``first_``); with ``lean`` also
    benchmarks/graphs/rt_hybrid_lean.yaml (no wavefront passes: ``lean_``).
    ``dump``: a folder for ``SCENE_CAMERA.npz`` (the colour images as float16, the visibility ids)."""
    from rgraph.passes.raytrace_hybrid import prim_bits

    from rgraph.compiler.pipeline import compile_graph
    from rgraph.scene.build import load_scene_data

    path = scene_file(scene)
    params = {"rt.max_depth": str(depth)}
    levels = tuple(f"rays_{k}_args" for k in range(1, WAVE_LEVELS + 1))
    graphs = {"alone": ("rt_standalone", ()),
              "hybrid": ("rt_hybrid", ("ray_args", "visibility", "vis_jobs", *levels))}
    if raster:
        graphs["raster"] = (RASTER_GRAPH, ("visibility",))
    if async_shade:
        graphs["async"] = (str(ASYNC_GRAPH), ("ray_args",))
    if every_shadow_ray:
        graphs["traced"] = ("rt_hybrid", ())
    if first:
        graphs["first"] = (str(FIRST_GRAPH), ("first_args",))
    if lean:
        graphs["lean"] = (str(LEAN_GRAPH), ())
    own = {"hybrid": {**params, **(hybrid_params or {})}, "traced": {**params, **(hybrid_params or {}), "rt.light_maps": "0"},
           "first": {**params, **(hybrid_params or {})}, "lean": {**params, **(hybrid_params or {})}}
    plans = {name: compile_graph(graph, scene_path=path, size=size, camera=camera, params=own.get(name, params),
                                 extra_outputs=list(extra), memory=gpu.memory_requirements())
             for name, (graph, extra) in graphs.items()}
    runs = side_by_side(gpu, plans, frames, warmup_s, chunk)
    alone, hybrid = runs["alone"], runs["hybrid"]
    T = alone["timings"]["total_ms"]
    out = hybrid["outputs"]
    data = load_scene_data(path, size, camera)  # the row's scene: classified pixels, primitive bits
    traced = int(np.frombuffer(out["ray_args"].tobytes()[:16], dtype=np.uint32)[3]) if "ray_args" in out else 0
    if not traced:  # in-thread (rt.wavefront 0): no pixel list; the pixels whose surface needs secondary rays
        traced = classified_pixels(out["visibility"][..., 0], data)
    row = {"scene": scene, "camera": camera, "size": list(size), "frames": frames, "max_depth": depth,
           "hybrid_params": hybrid_params or {},
           "warmup_s": warmup_s, "T_ms": T, **_hybrid_columns(hybrid["timings"], T, out, alone["outputs"]),
           "traced_share": traced / (size[0] * size[1]),
           "boundary_share": boundary_share(out["visibility"][..., 0], prim_bits(data))}

    if dump is not None:
        dump.mkdir(parents=True, exist_ok=True)
        more = {"async": runs["async"]["outputs"]["color"].astype(np.float16)} if async_shade else {}
        np.savez_compressed(dump / f"{scene}_{camera}.npz", alone=alone["outputs"]["color"].astype(np.float16),
                            hybrid=out["color"].astype(np.float16), visibility=out["visibility"][..., 0], **more)
    lists = [np.frombuffer(out[name].tobytes()[:16], dtype=np.uint32) for name in levels if name in out]
    row.update(level_rays=[traced] + [int(a[0]) for a in lists], level_overflow=any(bool(a[3]) for a in lists))
    if "vis_jobs" in out:  # the compute visibility buffer's tile jobs (overflow: the slow in-thread fallback ran)
        header = np.frombuffer(out["vis_jobs"].tobytes()[:8], dtype=np.uint32)
        row.update(vis_jobs=int(header[0]), vis_overflow=bool(header[1]))
    if async_shade:
        row.update(_hybrid_columns(runs["async"]["timings"], T, runs["async"]["outputs"], alone["outputs"], "async_"))
    if every_shadow_ray:
        row.update(_hybrid_columns(runs["traced"]["timings"], T, runs["traced"]["outputs"], alone["outputs"], "traced_"))
    if first:
        listed = runs["first"]["outputs"]["first_args"].tobytes()[:4]  # pixels handed to the shade pass's trace
        row.update(_hybrid_columns(runs["first"]["timings"], T, runs["first"]["outputs"], alone["outputs"], "first_"),
                   first_listed_share=int(np.frombuffer(listed, dtype=np.uint32)[0]) / (size[0] * size[1]))
    if lean:
        row.update(_hybrid_columns(runs["lean"]["timings"], T, runs["lean"]["outputs"], alone["outputs"], "lean_"))
    if raster:
        raster_out = runs["raster"]["outputs"]
        row.update(_hybrid_columns(runs["raster"]["timings"], T, raster_out, alone["outputs"], "raster_"))
        ids, raster_ids = out["visibility"][..., 0], raster_out["visibility"][..., 0]
        # diagnosis of the two visibility buffers: ids that differ, and compute holes (0 where the raster has an id)
        row.update(vis_differs_share=float((ids != raster_ids).mean()),
                   vis_holes_share=float(((ids == 0) & (raster_ids != 0)).mean()))
    return row


def classified_pixels(ids: np.ndarray, data: Any) -> int:
    """Pixels whose visible surface reflects or refracts (the ones classify.comp would list);
    ``data``: the row's ``SceneData``."""
    from rgraph.passes.raytrace_hybrid import (
        decode_visibility,
        instance_materials,
        needs_secondary_rays,
        prim_bits,
    )

    inst, _prim = decode_visibility(ids, prim_bits(data))
    mask = needs_secondary_rays(data.materials)[instance_materials(data)]
    return int(mask[inst[inst >= 0]].sum())


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


def scene_file(scene: str) -> Path:
    """A bundled scene's name (``graphs/scenes/NAME.yaml``) or a scene file's path (``*.yaml``)."""
    return Path(scene).resolve() if scene.endswith(".yaml") else ROOT / "graphs" / "scenes" / f"{scene}.yaml"


def depth_sweep(scene: str, camera: int, size: tuple[int, int], frames: int) -> list[dict[str, Any]]:
    """Stand-alone and hybrid at rt.max_depth 1..8 against the stand-alone depth-16 image."""
    path = scene_file(scene)
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


def _levels(row: dict[str, Any]) -> str:
    rays = row.get("level_rays")
    return "-" if not rays else " / ".join(str(n) for n in rays) + (" (overflow)" if row.get("level_overflow") else "")


def table(rows: list[dict[str, Any]]) -> str:
    raster = any("raster_t_ms" in r for r in rows)
    variants = [(prefix, label) for prefix, label in VARIANTS if any(f"{prefix}t_ms" in r for r in rows)]
    first = any("first_t_ms" in r for r in rows)
    head = ("| scene | camera | T (ms) | t_a (ms) | t_a/T | t_b (ms) | t (ms) | t/T | PSNR (dB) | SSIM | FLIP "
            "| traced | rays per level | primary traced |" + (" raster t_b (ms) | raster t (ms) | raster t/T | raster PSNR (dB) |" if raster else "")
            + "".join(f" {label} t (ms) | {label} t/T | {label} PSNR (dB) |" for _p, label in variants)
            + (" first listed |" if first else "")
            + "\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|---:|---:|---:|" if raster else "")
            + "---:|---:|---:|" * len(variants) + ("---:|" if first else ""))
    lines = [head]
    for r in rows:
        line = (f"| {r['scene']} | {r['camera']} | {r['T_ms']:.3f} | {r['t_a_ms']:.3f} | {r['t_a_over_T']:.2f} "
                f"| {r['t_b_ms']:.3f} | {r['t_ms']:.3f} | {r['t_over_T']:.2f} | {_fmt(r['psnr_db'], '.1f')} "
                f"| {_fmt(r['ssim'], '.4f')} | {_fmt(r['flip'], '.4f')} | {r['traced_share']:.1%} "
                f"| {_levels(r)} | {r['boundary_share']:.1%} |")
        if raster:
            line += (f" {r['raster_t_b_ms']:.3f} | {r['raster_t_ms']:.3f} | {r['raster_t_over_T']:.2f} "
                     f"| {_fmt(r['raster_psnr_db'], '.1f')} |") if "raster_t_ms" in r else " - | - | - | - |"
        for prefix, _label in variants:
            line += (f" {r[prefix + 't_ms']:.3f} | {r[prefix + 't_over_T']:.2f} | {_fmt(r[prefix + 'psnr_db'], '.1f')} |"
                     if f"{prefix}t_ms" in r else " - | - | - |")
        if first:
            line += f" {r['first_listed_share']:.1%} |" if "first_listed_share" in r else " - |"
        lines.append(line)
    return "\n".join(lines)


def pass_table(rows: list[dict[str, Any]]) -> str:
    """The hybrid's per-pass medians (ms; each pass's timestamp pair, so overlapping passes
    overlap here too)."""
    names = [n for n in rows[0].get("passes", {}) if n not in ("build_as",)] if rows else []
    lines = ["| scene | camera | " + " | ".join(names) + " |", "|---|---:|" + "---:|" * len(names)]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['camera']} | "
                     + " | ".join(_fmt(r["passes"].get(n), ".3f") for n in names) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    from rgraph.resources import builtin_passes

    builtin_passes()  # rgraph.passes from a checkout without an install (the GPU machine)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", default="full", help="full (1280x720), small (64x36) or WxH")
    parser.add_argument("--frames", type=int, default=None, help="timed frames per plan (default 50; small: 2)")
    parser.add_argument("--warmup", type=float, default=None,
                        help=f"seconds of untimed frames of every plan first (default: {WARMUP_S} on a GPU, "
                             "0 on a CPU device: Gpu.default_warmup_s)")
    parser.add_argument("--chunk", type=int, default=CHUNK, help="frames per timed run (plans alternate)")
    parser.add_argument("--no-raster", action="store_true", help="skip the hardware-raster hybrid variant")
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--cameras", default="0,1,2,3,4")
    parser.add_argument("--max-depth", type=int, default=4)
    parser.add_argument("--async", dest="async_shade", action="store_true",
                        help="also time benchmarks/graphs/rt_hybrid_async.yaml (matte pixels shaded on the async queue)")
    parser.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                        help="a param of graphs/rt_hybrid.yaml for the hybrid (repeatable), e.g. rt.wave_subgroup=1")
    parser.add_argument("--depth-sweep", action="store_true", help="rt.max_depth 1..8 vs depth 16 (camera 0)")
    parser.add_argument("--traced", action="store_true",
                        help="also time the hybrid with rt.light_maps=0 (every shadow ray traced)")
    parser.add_argument("--lean", action="store_true",
                        help="also benchmarks/graphs/rt_hybrid_lean.yaml (the hybrid without its wavefront passes)")
    parser.add_argument("--first", action="store_true",
                        help="also the hybrid with a compute pass shading the pixels that need no ray")
    parser.add_argument("--json", type=Path, help="also write JSON lines here")
    parser.add_argument("--dump", type=Path, help="write each camera's two images (SCENE_CAMERA.npz) here")
    args = parser.parse_args(argv)
    size = SIZES.get(args.size) or tuple(int(v) for v in args.size.lower().split("x"))
    small = args.size == "small"
    frames = args.frames or (2 if small else 50)
    raster = not args.no_raster and (ROOT / "graphs" / f"{RASTER_GRAPH}.yaml").exists()
    scenes = [s for s in args.scenes.split(",") if s]
    hybrid_params = dict(kv.split("=", 1) for kv in args.param)
    rows: list[dict[str, Any]] = []
    if args.depth_sweep:
        for scene in scenes:
            rows += depth_sweep(scene, int(args.cameras.split(",")[0]), size, frames)
    else:
        from rgraph.api import open_device

        with open_device(validate=False, verbose=False) as gpu:  # one device for every plan of the run
            warmup = args.warmup if args.warmup is not None else gpu.default_warmup_s
            for scene in scenes:
                for camera in (int(c) for c in args.cameras.split(",") if c):
                    rows.append(measure(gpu, scene, camera, size, frames, args.max_depth, warmup_s=warmup,
                                        chunk=max(1, args.chunk), raster=raster, hybrid_params=hybrid_params,
                                        async_shade=args.async_shade, dump=args.dump, every_shadow_ray=args.traced,
                                        first=args.first, lean=args.lean))
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
        print("\nHybrid passes (median ms):\n")
        print(pass_table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
