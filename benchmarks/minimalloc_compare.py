"""Our MiniMalloc solver against google/minimalloc's C++ one on the challenging traces.

    .venv/bin/python benchmarks/minimalloc_compare.py [--minimalloc BIN] [--only A,B] [--budget S]

Per trace: the C++ solver at the trace's capacity (1,048,576, as its run-challenging.sh;
``BIN`` from ``tools/minimalloc/build.sh``), our Python port at the same capacity
(``search.solve_capacity``, round robin without limit), and the ``optimal`` policy
(``place_class(..., exact=True)`` at the default 10 s budget), with its ratio to the bound and
whether the result is proven optimal (at the bound, or the capacity just below proven
infeasible). Wall seconds; run them on the same machine at the same time for a fair race.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from placement import shared_dir  # noqa: E402

from rgraph.memory import OPTIMAL_BUDGET_S  # noqa: E402
from rgraph.memory.aliased import place_class  # noqa: E402
from rgraph.memory.instance import Instance  # noqa: E402
from rgraph.memory.search import solve_capacity  # noqa: E402
from rgraph.memory.trace import read_trace  # noqa: E402


def cpp_seconds(binary: str, path: Path, capacity: int) -> str:
    out = subprocess.run([binary, str(path), str(capacity)], capture_output=True, text=True, check=True).stdout
    words = out.split()
    return f"{float(words[words.index('seconds') + 1]):.2f}s" + ("" if "height" in words else " (no)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minimalloc", help="the C++ driver built by tools/minimalloc/build.sh")
    parser.add_argument("--only", help="comma-separated trace letters")
    parser.add_argument("--budget", type=float, default=OPTIMAL_BUDGET_S, help="optimal's budget, seconds")
    args = parser.parse_args()
    print(f"{'trace':<6}{'blocks':>7}{'bound':>9}{'C++ @cap':>11}{'ours @cap':>11}{'optimal':>9}{'ratio':>8}  proven")
    for path in sorted((shared_dir() / "data/minimalloc").glob("*.csv")):
        name = path.stem.split(".")[0]
        if args.only and name not in args.only.split(","):
            continue
        capacity = int(path.stem.split(".")[1])
        inst = Instance.build(read_trace(path))
        cpp = cpp_seconds(args.minimalloc, path, capacity) if args.minimalloc else "-"
        began = time.perf_counter()
        found, _, _ = solve_capacity(inst, capacity, 1 << 60)
        ours = f"{time.perf_counter() - began:.2f}s" + ("" if found is not None else " (no)")
        began = time.perf_counter()
        result = place_class(inst, args.budget, exact=True)
        optimal = time.perf_counter() - began
        print(f"{name:<6}{inst.n:>7}{inst.lower_bound():>9}{cpp:>11}{ours:>11}{optimal:>8.2f}s"
              f"{result.peak / result.lower_bound:>7.3f}x  {'yes' if result.proven else 'no'}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
