"""Every bundled graph against every bundled scene and the edge-case scenes of
``benchmarks/sweep_scenes/`` at small and odd sizes, through ``rgraph run`` on the default
device (lavapipe here), one subprocess per combination; prints one classified row each.

    python benchmarks/sweep_combinations.py [--sizes 32x18] [--odd-sizes 1x1,2x2,7x3,33x17]
        [--odd-scenes rt_tiny,cct,tiny_mesh,lights_17] [--extreme-sizes 4096x1,1x4096]
        [--extreme-scenes rt_tiny] [--graphs a,b] [--scenes a,b] [--skip a,b]
        [--timeout 60] [--jobs 2] [--frames 2]

Every combination runs ``rgraph run G --scene S --size WxH --frames F --validate --json --out
PNG``; a graph with ray tracing passes, which the installed validation layer cannot take
(``rgraph run`` refuses ``--validate`` for them), is rerun with ``--check-data`` instead (mode
``data``). ``--sizes`` cross every graph with every scene; ``--odd-sizes`` only with
``--odd-scenes``, ``--extreme-sizes`` with ``--extreme-scenes``. The VR scenes (thousands
of objects) take a few seconds at these sizes on lavapipe; ``--skip`` leaves scenes out.

Classes: ``OK`` (exit 0, no validation message, data check ok or not applicable, an image
that is not all transparent; its mean colour and colour count are printed for a look);
``REFUSED`` (exit 2 with one ``FILE:LINE:COL: error:`` diagnostic, no traceback: bad input
refused as docs/format.md says); ``BUG`` (anything else: a traceback, another exit status,
validation messages, a failed data check, a timeout, a refusal without a location, an
all-transparent PNG).
Exits 1 if any row is a BUG. Not part of CI (minutes of lavapipe time).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EDGE_SCENES = ROOT / "benchmarks" / "sweep_scenes"
RT_REFUSAL = "vkCreateRayTracingPipelinesKHR"


@dataclass(frozen=True)
class Case:
    graph: str
    scene: Path
    size: str


@dataclass(frozen=True)
class Result:
    case: Case
    mode: str
    verdict: str
    seconds: float
    detail: str


def _rgraph() -> list[str]:
    exe = Path(sys.executable).with_name("rgraph")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rgraph"]


def _image_note(png: Path) -> str:
    """Mean RGB and distinct colours of the output PNG (an all-flat image is worth a look)."""
    try:
        import numpy as np
        from PIL import Image
    except ImportError:
        return ""
    if not png.exists():
        return "no image"
    rgba = np.asarray(Image.open(png).convert("RGBA")).reshape(-1, 4)
    if not rgba[:, 3].any():
        return "BUG: an all-transparent image (the PNG writer did not understand the output)"
    pixels = rgba[:, :3]
    colours = len(np.unique(pixels, axis=0))
    mean = pixels.mean(axis=0)
    return f"img mean {mean[0]:.0f},{mean[1]:.0f},{mean[2]:.0f} {colours} colour(s)"


def _classify(proc: subprocess.CompletedProcess[str]) -> tuple[str, str]:
    err = proc.stderr.strip()
    if "Traceback" in err:
        return "BUG", "traceback: " + err.splitlines()[-1][:160]
    try:
        doc = json.loads(proc.stdout)
    except json.JSONDecodeError:
        return "BUG", f"exit {proc.returncode}, stdout not JSON: {(proc.stdout or err)[-160:]!r}"
    diags = doc.get("diagnostics", [])
    errors = [d for d in diags if d.get("severity") == "error"]
    if proc.returncode == 2:
        located = len(errors) == 1 and errors[0].get("line", 0) >= 1 and errors[0].get("file")
        text = "; ".join(f"{d.get('file')}:{d.get('line')}:{d.get('col')}: {d.get('message')}" for d in errors)
        device_failure = any(d.get("file") == "<device>" for d in errors)
        if located and not device_failure:
            return "REFUSED", text[:200]
        return "BUG", "exit 2: " + text[:200]
    if proc.returncode != 0:
        messages = doc.get("validation", {}).get("messages", [])
        check = doc.get("data_check") or {}
        why = messages[:1] or check.get("mismatches", [])[:1] or [e.get("message") for e in errors][:1]
        return "BUG", f"exit {proc.returncode}: {len(messages)} validation message(s); {(why or [''])[0][:200]}"
    messages = doc.get("validation", {}).get("messages", [])
    check = doc.get("data_check")
    if messages:
        return "BUG", f"exit 0 but {len(messages)} validation message(s): {messages[0][:160]}"
    if check is not None and not check.get("ok", False):
        return "BUG", "exit 0 but data check failed"
    warnings = [d.get("message", "") for d in diags if d.get("severity") == "warning"]
    note = f"{len(warnings)} warning(s): {warnings[0][:100]}" if warnings else ""
    return "OK", note


def run_case(case: Case, frames: int, timeout: float) -> Result:
    with tempfile.TemporaryDirectory() as tmp:
        png = Path(tmp) / "out.png"
        base = [*_rgraph(), "run", case.graph, "--scene", str(case.scene.relative_to(ROOT)), "--size", case.size,
                "--frames", str(frames), "--json", "--out", str(png)]
        start = time.perf_counter()
        mode = "validate"
        try:
            proc = subprocess.run([*base, "--validate"], capture_output=True, text=True, timeout=timeout, cwd=ROOT)
            if proc.returncode == 2 and RT_REFUSAL in proc.stdout:
                mode = "data"
                proc = subprocess.run([*base, "--check-data"], capture_output=True, text=True, timeout=timeout,
                                      cwd=ROOT)
        except subprocess.TimeoutExpired:
            return Result(case, mode, "BUG", time.perf_counter() - start, f"timeout after {timeout:.0f} s")
        seconds = time.perf_counter() - start
        verdict, detail = _classify(proc)
        if verdict == "OK":
            image = _image_note(png)
            if image.startswith("BUG: "):
                verdict, image = "BUG", image[len("BUG: "):]
            detail = "; ".join(x for x in (image, detail) if x)
        return Result(case, mode, verdict, seconds, detail)


def _names(folder: Path) -> dict[str, Path]:
    return {p.stem: p for p in sorted(folder.glob("*.yaml"))}


def cases(args: argparse.Namespace) -> list[Case]:
    graphs = sorted(_names(ROOT / "graphs"))
    scenes = {**_names(ROOT / "graphs" / "scenes"), **_names(EDGE_SCENES)}
    scenes = {k: v for k, v in scenes.items() if k not in args.skip.split(",")}
    if args.graphs:
        graphs = [g for g in graphs if g in args.graphs.split(",")]
    if args.scenes:
        scenes = {k: v for k, v in scenes.items() if k in args.scenes.split(",")}
    out = [Case(g, s, size) for size in args.sizes.split(",") if size for g in graphs for s in scenes.values()]
    odd = [s for k, s in scenes.items() if k in args.odd_scenes.split(",")]
    out += [Case(g, s, size) for size in args.odd_sizes.split(",") if size for g in graphs for s in odd]
    extreme = [s for k, s in scenes.items() if k in args.extreme_scenes.split(",")]
    out += [Case(g, s, size) for size in args.extreme_sizes.split(",") if size for g in graphs for s in extreme]
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default="32x18")
    parser.add_argument("--odd-sizes", default="1x1,2x2,7x3,33x17")
    parser.add_argument("--odd-scenes", default="rt_tiny,cct,tiny_mesh,lights_17")
    parser.add_argument("--graphs", default="")
    parser.add_argument("--scenes", default="")
    parser.add_argument("--extreme-sizes", default="4096x1,1x4096")
    parser.add_argument("--extreme-scenes", default="rt_tiny")
    parser.add_argument("--skip", default="", help="scene names to leave out")
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--frames", type=int, default=2)
    args = parser.parse_args(argv)
    todo = cases(args)
    print(f"# rgraph run sweep: {len(todo)} combination(s), frames {args.frames}, timeout {args.timeout:.0f} s, "
          f"jobs {args.jobs}, load {os.getloadavg()[0]:.2f}", flush=True)
    print(f"{'graph':<18} {'scene':<17} {'size':<6} {'mode':<8} {'verdict':<7} {'s':>5}  detail", flush=True)
    counts: dict[str, int] = {}
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for r in pool.map(lambda c: run_case(c, args.frames, args.timeout), todo):
            counts[r.verdict] = counts.get(r.verdict, 0) + 1
            print(f"{r.case.graph:<18} {r.case.scene.stem:<17} {r.case.size:<6} {r.mode:<8} {r.verdict:<7} "
                  f"{r.seconds:5.1f}  {r.detail}", flush=True)
    print("# " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())), flush=True)
    return 1 if counts.get("BUG") else 0


if __name__ == "__main__":
    sys.exit(main())
