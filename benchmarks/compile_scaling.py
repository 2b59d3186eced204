"""Median compile time (parsed spec -> plan) for random graphs of 250 .. 16k passes.

    .venv/bin/python benchmarks/compile_scaling.py [--sizes 250,1000,4000,16000] [--policy aliased]

Prints one row per size and the growth exponent fitted on log(time) vs log(passes).
Target (issue 2): 1,000 passes in at most 16 ms; exponent at most 1.15.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rgraph.compiler.pipeline import compile_plan, frontend  # noqa: E402
from rgraph.random_graph import random_graph, to_yaml  # noqa: E402


def measure(passes: int, policy: str, repeats: int) -> tuple[float, int, int]:
    graph = random_graph(seed=passes, passes=passes)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "g.yaml"
        path.write_text(to_yaml(graph))
        spec = frontend(path, size=(16, 16)).spec
    times = []
    plan = {}
    for _ in range(repeats):
        start = time.perf_counter()
        plan = compile_plan(spec, policy=policy)
        times.append(time.perf_counter() - start)
    return statistics.median(times), len(plan.passes), plan.stats.barriers


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", default="250,1000,4000,16000")
    parser.add_argument("--policy", default="aliased")
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    rows = []
    print(f"{'passes':>8} {'executed':>9} {'barriers':>9} {'median ms':>10} {'us/pass':>8}")
    for n in sizes:
        median, executed, barriers = measure(n, args.policy, repeats=max(3, min(15, 16000 // n)))
        rows.append((n, median))
        print(f"{n:>8} {executed:>9} {barriers:>9} {median * 1e3:>10.1f} {median / n * 1e6:>8.1f}")
    xs = [math.log(n) for n, _ in rows]
    ys = [math.log(t) for _, t in rows]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum((x - mx) ** 2 for x in xs)
    print(f"growth exponent: {slope:.2f}  (policy {args.policy})")


if __name__ == "__main__":
    main()
