"""The accuracy-vs-time sweeps (benchmarks/sweeps.py) in worker processes vs one process:
throughput, identical outputs, and what sharing one GPU does to the measured times.

    python3 benchmarks/sweep_throughput.py [--size 1920x1080] [--frames 30]
        [--groups hbao,sss,bloom,shadow,ibl] [--workers 2,4,8] -o DIR [--json FILE]

Baseline: every group in its own process, one after the other (``benchmarks/sweeps.py
--groups G``; the NVIDIA driver refuses instances after ~40 in one process, so one process
for all groups is not possible there). Then all groups in one command with ``--workers N``
for each N. Per run: wall seconds, renderings per minute and the speedup over the baseline;
per group, whether every output but the times is the same as the baseline's
(:mod:`rgraph.sweep.same`), and the median and largest relative change of a setting's frame
GPU time (N renderings share one GPU: times under N > 1 include the others' work).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

SWEEPS = ROOT / "benchmarks" / "sweeps.py"


def sweeps(args: list[str]) -> tuple[float, int, str]:
    """Run benchmarks/sweeps.py: (wall seconds, renderings, stderr)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    started = time.perf_counter()
    done = subprocess.run([sys.executable, str(SWEEPS), "--no-progress", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"sweep_throughput: {' '.join(args)} failed ({done.returncode}):\n{done.stderr[-3000:]}")
    renderings = sum(int(n) for n in re.findall(r"\((\d+) renderings\)", done.stderr))
    return wall, renderings, done.stderr


def main(argv: list[str] | None = None) -> int:
    from rgraph.sweep.same import differences, relative_time_changes

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="1920x1080")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--groups", default="hbao,sss,bloom,shadow,ibl")
    parser.add_argument("--workers", default="2,4,8", help="comma-separated worker counts")
    parser.add_argument("-o", "--out", type=Path, required=True)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    groups = [g for g in args.groups.split(",") if g]
    common = ["--size", args.size, "--frames", str(args.frames)]
    one = args.out / "one"
    wall, renderings = 0.0, 0
    for group in groups:
        w, r, _ = sweeps([*common, "--groups", group, "-o", str(one)])
        wall, renderings = wall + w, renderings + r
        print(f"one process: {group}: {r} renderings in {w:.1f} s", file=sys.stderr, flush=True)
    runs = [{"workers": 1, "how": "one process per group", "wall_s": round(wall, 2), "renderings": renderings}]

    def save() -> None:  # after every run: a run cut short keeps what was measured
        if args.json:
            args.json.write_text(json.dumps({"size": args.size, "frames": args.frames, "runs": runs}, indent=1) + "\n")

    save()
    for n in [int(x) for x in args.workers.split(",") if x]:
        out = args.out / f"workers{n}"
        w, r, _ = sweeps([*common, "--groups", ",".join(groups), "--workers", str(n), "-o", str(out)])
        run = {"workers": n, "how": f"--workers {n}", "wall_s": round(w, 2), "renderings": r, "groups": {}}
        for group in groups:
            changes = relative_time_changes(one / group, out / group)
            run["groups"][group] = {
                "differences": differences(one / group, out / group),
                "time_change_median": round(statistics.median(changes), 4) if changes else None,
                "time_change_max": round(max(changes), 4) if changes else None}
        runs.append(run)
        save()
        print(f"--workers {n}: {r} renderings in {w:.1f} s", file=sys.stderr, flush=True)
    base = runs[0]["wall_s"] / max(runs[0]["renderings"], 1)
    print(f"{'run':<22} {'wall s':>8} {'renderings':>10} {'per min':>8} {'speedup':>8}  same outputs (but times); "
          "frame-time change vs one process, median / max")
    for run in runs:
        per = run["wall_s"] / max(run["renderings"], 1)
        run["per_minute"] = round(60.0 / per, 2) if per else None
        run["speedup"] = round(base / per, 2) if per else None
        same = "; ".join(f"{g}: {'yes' if not v['differences'] else 'NO ' + ','.join(v['differences'][:3])} "
                         f"{v['time_change_median']} / {v['time_change_max']}" for g, v in run.get("groups", {}).items())
        print(f"{run['how']:<22} {run['wall_s']:>8.1f} {run['renderings']:>10} {run['per_minute']:>8} "
              f"{run['speedup']:>8}  {same or 'baseline'}")
    save()
    return 0 if all(not v["differences"] for run in runs[1:] for v in run["groups"].values()) else 1


if __name__ == "__main__":
    sys.exit(main())
