"""The committed sweeps (benchmarks/sweeps.py) through one worker pool vs one process per
group: throughput, identical outputs, GPU memory per worker, and what sharing one GPU does
to the measured times.

    python3 benchmarks/sweep_throughput.py [--size 1280x720] [--frames 10]
        [--groups hbao,sss,rt,clusters] [--pools 4x8,8x8,8x1] -o DIR [--json FILE]

Baseline: every group in its own process, one after the other (``benchmarks/sweeps.py
--groups G``, the one-process ``rgraph sweep`` of each group; the NVIDIA driver refuses
instances after ~40 in one process, so one process for all groups is not possible there).
Then, for each ``NxK`` of ``--pools``, the same groups in ONE command through one pool of N
worker processes, each rendering K settings before a fresh one takes its place
(``benchmarks/sweeps.py --groups ... --workers N --per-worker K``). Per run: wall seconds,
renderings per second and the ratio to the baseline's; the peak GPU memory in use above the
idle level and its share per worker, and the mean GPU utilization (``nvidia-smi``, sampled
every 0.5 s; empty without it); per group, whether every output but the times equals the
baseline's (:mod:`rgraph.sweep.same`), and the median and largest relative change of a
setting's frame GPU time (N renderings share one GPU: times under N > 1 include the
others' work).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

SWEEPS = ROOT / "benchmarks" / "sweeps.py"
QUERY = ["nvidia-smi", "--query-gpu=memory.used,memory.total,utilization.gpu", "--format=csv,noheader,nounits"]


class GpuSampler:
    """``nvidia-smi`` every ``period`` s in a thread: GPU 0's memory used (MiB) and utilization (%)."""

    def __init__(self, period: float = 0.5) -> None:
        self.period, self.samples = period, []
        self.total_mib: float | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    @staticmethod
    def read() -> tuple[float, float, float] | None:
        """(used MiB, total MiB, utilization %) of GPU 0, or None without nvidia-smi."""
        if shutil.which(QUERY[0]) is None:
            return None
        try:
            line = subprocess.run(QUERY, capture_output=True, text=True, timeout=10).stdout.splitlines()[0]
            used, total, util = (float(x) for x in line.split(","))
        except (OSError, ValueError, IndexError, subprocess.SubprocessError):
            return None
        return used, total, util

    def _loop(self) -> None:
        while not self._stop.is_set():
            sample = self.read()
            if sample is None:
                return
            self.total_mib = sample[1]
            self.samples.append((sample[0], sample[2]))
            self._stop.wait(self.period)

    def __enter__(self) -> GpuSampler:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def summary(self, idle_mib: float | None, workers: int) -> dict:
        if not self.samples or idle_mib is None:
            return {}
        peak = max(s[0] for s in self.samples) - idle_mib
        return {"gpu_mem_peak_mib": round(peak), "gpu_mem_per_worker_mib": round(peak / workers),
                "gpu_mem_total_mib": self.total_mib,
                "gpu_util_mean": round(statistics.fmean(s[1] for s in self.samples), 1),
                "workers_fit_by_memory": int(self.total_mib // max(peak / workers, 1.0)) if self.total_mib else None}


def sweeps(args: list[str], log: Path) -> tuple[float, int, int]:
    """Run benchmarks/sweeps.py (its stderr into ``log``): (wall seconds, renderings, exit code)."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    started = time.perf_counter()
    done = subprocess.run([sys.executable, str(SWEEPS), "--no-progress", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - started
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("a") as f:
        f.write(f"$ sweeps.py {' '.join(args)}\n{done.stderr}\n")
    if done.returncode not in (0, 1):
        raise SystemExit(f"sweep_throughput: {' '.join(args)} failed ({done.returncode}):\n{done.stderr[-3000:]}")
    found = re.search(r"sweeps: (\d+) renderings in", done.stderr)
    return wall, int(found.group(1)) if found else 0, done.returncode


def compare(one: Path, out: Path, groups: list[str]) -> dict:
    from rgraph.sweep.same import differences, relative_time_changes

    report = {}
    for group in groups:
        if not (out / group / "sweep.csv").is_file() or not (one / group / "sweep.csv").is_file():
            report[group] = {"differences": ["missing"], "time_change_median": None, "time_change_max": None}
            continue
        changes = relative_time_changes(one / group, out / group)
        report[group] = {"differences": differences(one / group, out / group),
                         "time_change_median": round(statistics.median(changes), 4) if changes else None,
                         "time_change_max": round(max(changes), 4) if changes else None}
    return report


def table(runs: list[dict]) -> list[str]:
    base = runs[0]["per_s"]
    lines = [f"{'run':<34} {'wall s':>7} {'rend.':>5} {'rend./s':>8} {'ratio':>6} {'GPU MiB':>8} {'MiB/wkr':>8} "
             f"{'fit':>5} {'util%':>6}  same outputs (but times); frame-time change vs baseline, median / max"]
    for run in runs:
        run["ratio"] = round(run["per_s"] / base, 2) if base else None
        same = "; ".join(f"{g}: {'yes' if not v['differences'] else 'NO ' + ','.join(v['differences'][:3])} "
                         f"{v['time_change_median']} / {v['time_change_max']}" for g, v in run.get("groups", {}).items())
        lines.append(f"{run['how']:<34} {run['wall_s']:>7.1f} {run['renderings']:>5} {run['per_s']:>8.3f} "
                     f"{run['ratio']!s:>6} {run.get('gpu_mem_peak_mib', '')!s:>8} "
                     f"{run.get('gpu_mem_per_worker_mib', '')!s:>8} {run.get('workers_fit_by_memory', '')!s:>5} "
                     f"{run.get('gpu_util_mean', '')!s:>6}  {same or 'baseline'}")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="1280x720")
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("--groups", default="hbao,sss,rt,clusters", help="groups of benchmarks/sweeps.py")
    parser.add_argument("--pools", default="4x8,8x8,8x1",
                        help="comma-separated NxK: N worker processes, K settings each (default 4x8,8x8,8x1)")
    parser.add_argument("--workers", help="comma-separated N: the pools Nx1 (session 7's form; overrides --pools)")
    parser.add_argument("-o", "--out", type=Path, required=True, help="folder of every run's sweeps and logs")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    groups = [g for g in args.groups.split(",") if g]
    common = ["--size", args.size, "--frames", str(args.frames)]
    one, log = args.out / "one", args.out / "sweeps.log"
    idle = GpuSampler.read()
    idle_mib = idle[0] if idle else None
    runs: list[dict] = []

    def save() -> None:  # after every run: a run cut short keeps what was measured
        if args.json:
            args.json.write_text(json.dumps({"size": args.size, "frames": args.frames, "groups": groups,
                                             "idle_gpu_mib": idle_mib, "runs": runs}, indent=1) + "\n")

    wall = renderings = 0
    with GpuSampler() as sampler:
        for group in groups:
            w, r, _ = sweeps([*common, "--groups", group, "-o", str(one)], log)
            wall, renderings = wall + w, renderings + r
            print(f"one process: {group}: {r} renderings in {w:.1f} s", file=sys.stderr, flush=True)
    runs.append({"workers": 1, "how": "one process per group", "wall_s": round(wall, 2), "renderings": renderings,
                 "per_s": round(renderings / wall, 4) if wall else 0.0, **sampler.summary(idle_mib, 1)})
    save()
    if args.workers:
        args.pools = ",".join(f"{n}x1" for n in args.workers.split(",") if n)
    try:
        pools = [(int(n), int(k)) for n, _, k in (x.lower().partition("x") for x in args.pools.split(",") if x)]
    except ValueError:
        parser.error(f"--pools: NxK expected, got {args.pools!r}")
    for n, k in pools:
        out = args.out / f"pool{n}x{k}"
        with GpuSampler() as sampler:
            w, r, _ = sweeps([*common, "--groups", ",".join(groups), "--workers", str(n), "--per-worker", str(k),
                              "-o", str(out)], log)
        runs.append({"workers": n, "per_worker": k, "how": f"one pool of {n}, {k} settings/worker",
                     "wall_s": round(w, 2), "renderings": r, "per_s": round(r / w, 4) if w else 0.0,
                     **sampler.summary(idle_mib, n), "groups": compare(one, out, groups)})
        save()
        print(f"one pool of {n}, {k} settings per worker: {r} renderings in {w:.1f} s", file=sys.stderr, flush=True)
    print(f"size {args.size}, {args.frames} frames per setting, groups {','.join(groups)}; "
          f"idle GPU memory {idle_mib} MiB; 'fit': GPU memory / per-worker peak")
    print("\n".join(table(runs)))
    save()
    return 0 if all(not v["differences"] for run in runs[1:] for v in run["groups"].values()) else 1


if __name__ == "__main__":
    sys.exit(main())
