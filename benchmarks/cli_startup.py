"""Wall time of ``rgraph --help`` (issue 19: at most 150 ms) beside the bare interpreter.

    .venv/bin/python benchmarks/cli_startup.py [--runs 15] [--rgraph .venv/bin/rgraph]

Prints the minimum and median of ``--runs`` runs of each command: the installed ``rgraph``
script, ``python -m rgraph --help`` and ``python -c pass`` (the interpreter's own start).
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time


def timed(cmd: list[str], runs: int) -> tuple[float, float]:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - start)
    return min(times) * 1e3, statistics.median(times) * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--rgraph", default=shutil.which("rgraph"), help="the installed script (default: on PATH)")
    args = parser.parse_args()
    commands = [[sys.executable, "-m", "rgraph", "--help"], [sys.executable, "-c", "pass"]]
    if args.rgraph:
        commands.insert(0, [args.rgraph, "--help"])
    for cmd in commands:
        low, median = timed(cmd, args.runs)
        print(f"{' '.join(cmd):<60} min {low:6.1f} ms  median {median:6.1f} ms")


if __name__ == "__main__":
    main()
