"""The VR renderer study's benchmarks (issue 18): FPS, GPU busy and render-thread CPU per test.

Tests (graphs/clustered.yaml renders each): ``instanced`` (vr_instanced.yaml, 32,768 instanced
cubes), ``skinned`` (vr_skinned.yaml, 1,024 characters x 256 bones), ``lighting`` (lighting_test.yaml,
25 point lights over 968 boxes) and ``unique`` (vr_unique.yaml, 4,096 boxes with their own
geometry). Each runs mono and stereo (``-p views=2``, VK_KHR_multiview) and in two draw modes:
``gpu`` (persistent instances, GPU culling, one vkCmdDrawIndexedIndirectCount) and ``naive``
(``rgraph run --naive-cpu``: per-object CPU culling and one draw call per object).

Per run, after a warm-up of at least ``--warmup`` seconds of frames (the H200 starts at low
clocks; its first frames run ~3x slow):

- FPS = 1 / wall time per frame over ``--frames`` pipelined frames;
- GPU busy = the median timestamp span of a frame (first pass start to last pass end) / wall;
- render-thread CPU = per frame, the frame loop's time minus its fence wait
  (``benchmarks.frame_cpu.frame_parts``: Python and Vulkan calls, the host updates, the
  timestamp reads included): the mean over the timed frames (what the thread spends per frame,
  periodic work such as a logic tick's or a timestamp read's included) and the median; the
  medians of its Python and Vulkan-call parts;
- per pass, the GPU ms of stereo over mono (what doubles with the second eye, what more).

Each (test, views, mode) row runs in its own process with its own device (``--row``), so a
lost device or a crash costs that row only: the table then says ``failed (...)`` for it.

The render thread reads one frame's timestamps in ``--timestamps-every`` (default 4; the
per-pass medians then come from a quarter of the frames; the mean includes the reads).

    python3 -m benchmarks.vr_tests [--size 1920x1080] [--frames 300] [--warmup 0.5]
        [--tests instanced,skinned,lighting,unique] [--views 1,2] [--modes gpu,naive] [--logic-hz 60]
        [--timestamps-every 4] [--json OUT.json]
    python3 -m benchmarks.vr_tests --from-json gpu.json naive.json    # one table from two runs
    lavapipe smoke:  python3 -m benchmarks.vr_tests --size 160x90 --frames 3
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from rgraph.resources import builtin_passes

builtin_passes()  # rgraph.passes also from a plain checkout on PYTHONPATH (the GPU machines)
ROOT = Path(__file__).resolve().parent.parent
GRAPH = ROOT / "graphs" / "clustered.yaml"
SCENES = ROOT / "graphs" / "scenes"
TESTS = {"instanced": "vr_instanced.yaml", "skinned": "vr_skinned.yaml", "lighting": "lighting_test.yaml",
         "unique": "vr_unique.yaml"}
#: The study's figures (GTX 1080): GPU utilisation % / FPS of Ultra Engine.
STUDY = {"instanced": (95, 1206), "skinned": (96, 1179), "lighting": (96, 1456), "unique": (63, 6213)}


def available_tests(names: list[str]) -> list[str]:
    """The asked-for tests whose scene exists (vr_skinned.yaml comes with the skinning work)."""
    return [n for n in names if (SCENES / TESTS[n]).is_file()]


def load_kwargs(gpu: Any, logic_hz: float | None) -> dict[str, Any]:
    """Keyword arguments of ``gpu.load``: ``logic_hz`` where the runtime has a logic thread."""
    if logic_hz is None:
        return {}
    if "logic_hz" not in inspect.signature(gpu.load).parameters:
        raise SystemExit("vr_tests: --logic-hz needs the logic thread (rgraph run --logic-hz); this checkout lacks it")
    return {"logic_hz": logic_hz}


def measure(gpu: Any, test: str, size: tuple[int, int], views: int, mode: str, frames: int, warmup: float,
            logic_hz: float | None, timestamps_every: int = 1, extra: dict[str, str] | None = None) -> dict[str, Any]:
    from benchmarks.frame_cpu import frame_parts
    from rgraph.compiler.pipeline import compile_graph

    params = {**(extra or {}), "views": str(views), "draw.mode": mode}
    plan = compile_graph(GRAPH, scene_path=SCENES / TESTS[test], size=size, params=params,
                         memory=gpu.memory_requirements())
    marks: list[float] = []
    with gpu.load(plan, **load_kwargs(gpu, logic_hz)) as exe:
        exe.executor.timestamp_every = timestamps_every
        exe.warm_up(warmup)
        warmed = exe.run(3).frames  # frames run before timing (warm-up included)
        t0 = time.perf_counter()
        timings = exe.run(frames, marks=marks).timings
        wall_ms = (time.perf_counter() - t0) * 1000.0 / frames
        calls = len(exe.executor.submit_calls[0])
        draws = exe.executor.scene_gpu.draw_count
    parts = frame_parts(marks, calls, skip=0)
    span = timings["total_ms"]
    runtime = parts["runtime"]

    def median(key: str) -> float | None:
        return statistics.median(parts[key]) if parts[key] else None

    return {"test": test, "views": views, "mode": mode, "draws": draws, "warmup_frames": warmed,
            "wall_ms": wall_ms, "fps": 1000.0 / wall_ms, "gpu_span_ms": span,
            "gpu_busy": (span / wall_ms) if span is not None else None,
            "render_cpu_us": statistics.fmean(runtime) if runtime else None,
            "render_cpu_median_us": median("runtime"), "python_median_us": median("python"),
            "vulkan_median_us": median("vulkan"), "submit_median_us": median("submit"),
            "render_cpu_p90_us": _quantile(runtime, 0.9), "render_cpu_max_us": max(runtime) if runtime else None,
            "python_mean_us": _mean(parts["python"]), "vulkan_mean_us": _mean(parts["vulkan"]),
            "submit_mean_us": _mean(parts["submit"]),
            "timestamps_every": timestamps_every, "submits": calls, "logic": timings.get("logic"),
            "passes_ms": timings["passes"]}


ROW_PREFIX = "vr_tests-row: "


def _mean(values: list[float]) -> float | None:
    return statistics.fmean(values) if values else None


def _quantile(values: list[float], q: float) -> float | None:
    return sorted(values)[min(len(values) - 1, int(q * len(values)))] if values else None


def _one_row(args: argparse.Namespace, test: str, size: tuple[int, int], views: int, mode: str) -> int:
    """The child of ``_row_in_subprocess``: measure one row, print it as one JSON line."""
    import rgraph

    with rgraph.open_device(validate=False, verbose=False, one_queue=args.queues == "one") as gpu:
        extra = dict(kv.split("=", 1) for kv in args.param)
        r = measure(gpu, test, size, views, mode, args.frames, args.warmup, args.logic_hz, args.timestamps_every,
                    extra)
        r["params"] = extra
        r["device"] = gpu.choice.get("name", "?") if isinstance(gpu.choice, dict) else "?"
    print(ROW_PREFIX + json.dumps(r), flush=True)
    return 0


def _row_in_subprocess(argv: list[str], test: str, views: int, mode: str) -> dict[str, Any]:
    """One (test, views, mode) row measured in its own process and device, so a lost device
    or a crash costs that row only (an ``error`` row then)."""
    cmd = [sys.executable, "-m", "benchmarks.vr_tests", *argv, "--row", f"{test},{views},{mode}"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    for line in reversed(done.stdout.splitlines()):
        if line.startswith(ROW_PREFIX):
            return json.loads(line[len(ROW_PREFIX):])
    last = [ln for ln in (done.stderr + done.stdout).splitlines() if ln.strip()]
    return {"test": test, "views": views, "mode": mode,
            "error": f"exit {done.returncode}: {last[-1] if last else 'no output'}"}


def _f(v: float | None, fmt: str) -> str:
    return "-" if v is None else format(v, fmt)


def table(rows: list[dict[str, Any]]) -> str:
    """Markdown: a line per test and view count, gpu and naive side by side (a failed row: its
    FPS cell says so)."""
    head = ("| test | views | draws | FPS (gpu) | GPU busy (gpu) | render CPU us mean (gpu) | GPU ms (gpu) | "
            "FPS (naive) | GPU busy (naive) | render CPU us mean (naive) | stereo / mono frame (gpu) | study (Ultra) |")
    lines = [head, "|" + "---|" * 12]
    by = {(r["test"], r["views"], r["mode"]): r for r in rows}
    for test, views in dict.fromkeys((r["test"], r["views"]) for r in rows):
        g, n = by.get((test, views, "gpu"), {}), by.get((test, views, "naive"), {})
        mono = by.get((test, 1, "gpu"), {})
        ratio = (g["wall_ms"] / mono["wall_ms"]) if views > 1 and g.get("wall_ms") and mono.get("wall_ms") else None
        study = STUDY.get(test)
        draws = next((r["draws"] for r in (g, n) if r.get("draws")), "-")
        lines.append(
            f"| {test} | {views} | {draws} | {_fps(g)} | {_f(_pct(g.get('gpu_busy')), '.1f')}% | "
            f"{_f(g.get('render_cpu_us'), '.1f')} | {_f(g.get('gpu_span_ms'), '.3f')} | {_fps(n)} | "
            f"{_f(_pct(n.get('gpu_busy')), '.1f')}% | {_f(n.get('render_cpu_us'), '.1f')} | {_f(ratio, '.2f')} | "
            f"{'-' if not study or views > 1 else f'{study[0]}% / {study[1]}'} |")
    return "\n".join(lines)


def _fps(r: dict[str, Any]) -> str:
    if "error" in r:
        return "failed (" + r["error"].replace("|", "/")[:60] + ")"
    return _f(r.get("fps"), ".0f")


def pass_ratios(rows: list[dict[str, Any]]) -> str:
    """Markdown: per test (gpu mode), each pass's GPU ms mono, stereo and stereo / mono."""
    by = {(r["test"], r["views"]): r for r in rows if r["mode"] == "gpu" and "error" not in r}
    lines = ["| test | pass | mono ms | stereo ms | stereo / mono |", "|---|---|---:|---:|---:|"]
    for (test, views), mono in by.items():
        stereo = by.get((test, 2))
        if views != 1 or stereo is None:
            continue
        for name, a in mono["passes_ms"].items():
            b = stereo["passes_ms"].get(name)
            ratio = (b / a) if a and b is not None else None
            lines.append(f"| {test} | {name} | {_f(a, '.3f')} | {_f(b, '.3f')} | {_f(ratio, '.2f')} |")
        ratio = stereo["wall_ms"] / mono["wall_ms"]
        lines.append(f"| {test} | frame (wall) | {mono['wall_ms']:.3f} | {stereo['wall_ms']:.3f} | {ratio:.2f} |")
    return "\n".join(lines) if len(lines) > 2 else ""


def logic_summary(logic: dict[str, Any] | None) -> str:
    """``; logic ...``: the logic thread's kept rate (``LogicThread.stats``: with the ticks per
    running second, the runs, ticks behind at stop, the median tick delay), late ticks and tick
    time, and how its skinning states were evaluated (a worker process's evaluation time, the logic thread's wait)."""
    if not logic:
        return ""
    text = f"; logic {_f(logic.get('measured_hz'), '.1f')} Hz of {logic['hz']:g}"
    if "ticks_per_running_second" in logic:  # session 11: the kept rate, then the old figure
        text += (f" ({_f(logic['ticks_per_running_second'], '.1f')} ticks per running second over "
                 f"{logic['runs']} runs, {logic['behind_at_stop']} behind at stop, ticks "
                 f"{_f(logic.get('tick_delay_us'), '.0f')} us past due)")
    text += f", {logic['late_ticks']} late, tick {_f(logic.get('tick_us'), '.0f')} us on the logic thread"
    skin = logic.get("skin")
    if skin and skin.get("worker") == "process":
        text += (f" (skinning in a worker process, {skin['threads']} thread(s): "
                 f"{_f(skin.get('tick_us'), '.0f')} us per state, {_f(skin.get('tick_cpu_us'), '.0f')} us CPU, "
                 f"logic thread waits {_f(skin.get('wait_us'), '.0f')} us)")
    elif skin:
        text += f" (skinning on the logic thread, {skin['threads']} thread(s))"
    return text


def _pct(v: float | None) -> float | None:
    return None if v is None else 100.0 * v


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="1920x1080")
    parser.add_argument("--frames", type=int, default=300, help="timed frames per run")
    parser.add_argument("--warmup", type=float, default=0.5, help="seconds of frames before timing (>= 0.3)")
    parser.add_argument("--tests", default=",".join(TESTS))
    parser.add_argument("--views", default="1,2")
    parser.add_argument("--modes", default="gpu,naive", help="draw.mode values (gpu, naive, cpu)")
    parser.add_argument("--logic-hz", dest="logic_hz", type=float, default=None,
                        help="run scene logic on its own thread at this rate (needs rgraph run --logic-hz)")
    parser.add_argument("--timestamps-every", dest="timestamps_every", type=int, default=4,
                        help="read one frame's timestamps in this many (default 4; 1: every frame)")
    parser.add_argument("--json", type=Path, help="write every figure as JSON")
    parser.add_argument("--queues", choices=("device", "one"), default="device",
                        help="device: the plan's queues on the device's families (async compute); one: every "
                             "pass on one VkQueue (one vkQueueSubmit2 per frame)")
    parser.add_argument("-p", "--param", action="append", default=[], metavar="KEY=VALUE",
                        help="a graph param for every run (e.g. skin.threads=4, draw.naive=indirect)")
    parser.add_argument("--row", help=argparse.SUPPRESS)  # TEST,VIEWS,MODE: measure one row in this process
    parser.add_argument("--from-json", dest="from_json", type=Path, nargs="+",
                        help="measure nothing: print the tables of these --json files' rows together")
    args = parser.parse_args(argv)
    if args.from_json:
        docs = [json.loads(p.read_text()) for p in args.from_json]
        rows = [r for d in docs for r in d["rows"]]
        print(f"device: {docs[0].get('device', '?')}, {'x'.join(map(str, docs[0]['size']))}, from "
              + ", ".join(str(p) for p in args.from_json))
        print(table(rows))
        print(pass_ratios(rows))
        return 0
    if args.warmup < 0.3:
        parser.error("--warmup must be at least 0.3 s")
    if args.frames < 2:
        parser.error("--frames must be at least 2")
    w, h = (int(x) for x in args.size.lower().split("x"))
    asked = [t.strip() for t in args.tests.split(",") if t.strip()]
    unknown = [t for t in asked if t not in TESTS]
    if unknown:
        parser.error(f"unknown tests {unknown}; known: {', '.join(TESTS)}")
    tests = available_tests(asked)
    for missing in sorted(set(asked) - set(tests)):
        print(f"vr_tests: {missing}: skipped ({TESTS[missing]} does not exist)")
    if args.row:
        test, views, mode = args.row.split(",")
        return _one_row(args, test, (w, h), int(views), mode)
    rows = []
    device = "?"
    for test in tests:
        for views in (int(v) for v in args.views.split(",")):
            for mode in (m.strip() for m in args.modes.split(",")):
                r = _row_in_subprocess(argv if argv is not None else sys.argv[1:], test, views, mode)
                device = r.pop("device", device)
                rows.append(r)
                if "error" in r:
                    print(f"{test} views={views} {mode}: FAILED: {r['error']}", flush=True)
                    continue
                print(f"{test} views={views} {mode}: {r['fps']:.1f} FPS, GPU busy {_f(_pct(r['gpu_busy']), '.1f')}%, "
                      f"render CPU {_f(r['render_cpu_us'], '.1f')} us/frame mean, "
                      f"{_f(r['render_cpu_median_us'], '.1f')} median (Python {_f(r['python_median_us'], '.1f')}, "
                      f"Vulkan calls {_f(r['vulkan_median_us'], '.1f')}, of it submits "
                      f"{_f(r['submit_median_us'], '.1f')}; {r.get('submits', '?')} vkQueueSubmit2 per frame), "
                      f"p90 {_f(r.get('render_cpu_p90_us'), '.1f')}, means: Python {_f(r.get('python_mean_us'), '.1f')}, "
                      f"Vulkan {_f(r.get('vulkan_mean_us'), '.1f')}, "
                      f"GPU {_f(r['gpu_span_ms'], '.3f')} ms{logic_summary(r.get('logic'))}", flush=True)
    print(f"device: {device}, {w}x{h}, {args.frames} frames per run after >= {args.warmup} s of warm-up, "
          f"timestamps read every {args.timestamps_every} frames, queues: {args.queues}, logic thread "
          + (f"at {args.logic_hz:g} Hz" if args.logic_hz else "off"))
    print(table(rows))
    ratios = pass_ratios(rows)
    if ratios:
        print(ratios)
    if args.json:
        args.json.write_text(json.dumps({"size": [w, h], "device": device, "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
