"""Iterated greedy on the MiniMalloc challenging traces (an idea tried for issue 19 item 4).

    .venv/bin/python benchmarks/placement_iterated_greedy.py [--rounds 100]

Start from the best of the greedy orderings; each round moves one block at the peak, and
at random half of its neighbours whose tops lie within its size of the peak, to the front
of the current ordering and re-runs best fit; the result is kept when the peak does not
rise. Prints, per trace, the greedy and the final peak over the lower bound and the CPU
time, then the mean. (Result: far behind the capacity search; not used by ``aliased``.)
"""

from __future__ import annotations

import argparse
import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from placement import shared_dir  # noqa: E402

from rgraph.memory.greedy import best_fit, orderings  # noqa: E402
from rgraph.memory.instance import Instance  # noqa: E402
from rgraph.memory.trace import read_trace  # noqa: E402


def iterate(inst: Instance, rounds: int, seed: int = 1) -> tuple[int, int]:
    """(best greedy peak, final peak)."""
    best = None
    for _, order in orderings(inst):
        offsets = best_fit(inst, order)
        assert offsets is not None
        if best is None or inst.peak(offsets) < best[0]:
            best = (inst.peak(offsets), order, offsets)
    assert best is not None
    greedy = best[0]
    peak, order, offsets = best
    rng = random.Random(seed)
    for _ in range(rounds):
        tops = [offsets[i] + inst.size[i] for i in range(inst.n)]
        c = rng.choice([i for i in range(inst.n) if tops[i] == peak])
        movers = {c} | {j for j in inst.neighbors[c] if tops[j] > peak - inst.size[c] and rng.random() < 0.5}
        rank = {b: k for k, b in enumerate(order)}
        candidate = sorted(movers, key=rank.__getitem__) + [i for i in order if i not in movers]
        found = best_fit(inst, candidate, peak + 1)
        if found is not None:
            peak, order, offsets = inst.peak(found), candidate, found
    return greedy, peak


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rounds", type=int, default=100)
    args = parser.parse_args()
    ratios = []
    for path in sorted((shared_dir() / "data/minimalloc").glob("*.csv")):
        inst = Instance.build(read_trace(path))
        lb = inst.lower_bound()
        start = time.process_time()
        greedy, peak = iterate(inst, args.rounds)
        ratios.append((greedy / lb, peak / lb))
        print(f"{path.stem:<12} {inst.n:>4} blocks  greedy {greedy / lb:.3f}x -> {peak / lb:.3f}x  "
              f"{(time.process_time() - start) * 1e3:7.1f} ms cpu")
    if ratios:
        print(f"mean: greedy {sum(g for g, _ in ratios) / len(ratios):.3f}x -> "
              f"{sum(p for _, p in ratios) / len(ratios):.3f}x after {args.rounds} rounds")


if __name__ == "__main__":
    main()
