"""Placement benchmark: peak / lower bound and time per policy.

Instances: the MiniMalloc "challenging" traces in ``shared/data/minimalloc`` (beside the
repository, or ``$RGRAPH_SHARED``) and seeded random render-graph-like instances.
Run: ``.venv/bin/python benchmarks/placement.py [--quick] [--only LABELS] [--aliased-budgets 0.2,0.5]``.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rgraph.memory import Block, place  # noqa: E402
from rgraph.memory.random_instances import random_blocks  # noqa: E402
from rgraph.memory.trace import read_trace  # noqa: E402
from rgraph.memory.verify import overlaps  # noqa: E402

#: (label, policy, time budget or None for the policy's default)
POLICIES: list[tuple[str, str, float | None]] = [
    ("dedicated", "dedicated", None),
    ("blocks:16MiB", "blocks:16MiB", None),
    ("tlsf", "tlsf", None),
    ("aliased", "aliased", None),
    ("aliased@1s", "aliased", 1.0),
    ("optimal", "optimal", None),
]


def shared_dir() -> Path:
    env = os.environ.get("RGRAPH_SHARED")
    return Path(env) if env else Path(__file__).resolve().parents[2] / "shared"


def instances(quick: bool) -> list[tuple[str, str, list[Block]]]:
    """(group, name, blocks) for every instance."""
    found = []
    traces = shared_dir() / "data/minimalloc"
    if not traces.is_dir():
        print(f"note: no MiniMalloc traces at {traces} (set RGRAPH_SHARED): left out", file=sys.stderr)
    for path in sorted(traces.glob("*.csv")):
        found.append(("minimalloc", path.stem, read_trace(path)))
    for name, blocks in graph_instances():
        found.append(("graphs", name, blocks))
    for count in (50, 200, 1000):
        for seed in (1, 2) if quick else (1, 2, 3):
            found.append((f"random{count}", f"r{count}s{seed}", random_blocks(count, seed)))
    return found


def graph_instances(size: tuple[int, int] = (1920, 1080)) -> list[tuple[str, list[Block]]]:
    """The transient resources of each bundled graph (default scene) at ``size``, as blocks."""
    import rgraph
    from rgraph.resources import bundled_graphs

    out = []
    for name in bundled_graphs():
        plan = rgraph.compile(name, size=size, policy="dedicated").plan
        blocks = [
            Block(r.name, r.first, r.last, r.bytes, r.alignment, r.memory_class)
            for r in plan.resources
            if r.lifetime == "transient"
        ]
        out.append((f"{name}@{size[0]}x{size[1]}", blocks))
    return out


def print_graph_savings(size: tuple[int, int] = (1920, 1080)) -> None:
    """Whole-plan memory of each bundled graph per policy: peak, bound and saving vs unaliased."""
    import rgraph
    from rgraph.resources import bundled_graphs

    for name in bundled_graphs():
        for policy in ("dedicated", "aliased", "tlsf", "blocks:64MiB"):
            m = rgraph.compile(name, size=size, policy=policy).memory_analysis()
            st = {"peak_bytes": m.peak_bytes, "lower_bound_bytes": m.lower_bound_bytes,
                  "unaliased_bytes": m.unaliased_bytes}
            saving = 1 - st["peak_bytes"] / st["unaliased_bytes"]
            print(
                f"{name}@{size[0]}x{size[1]} {policy:<13} peak {st['peak_bytes'] / 2**20:8.1f} MiB  "
                f"bound {st['lower_bound_bytes'] / 2**20:8.1f} MiB  unaliased {st['unaliased_bytes'] / 2**20:8.1f} MiB  "
                f"saving {saving:6.1%}"
            )


def measure(blocks: Sequence[Block], policy: str, budget: float | None) -> tuple[float, float]:
    placement = place(blocks, policy, **({"time_budget_s": budget} if budget is not None else {}))
    problems = overlaps(blocks, placement)
    if problems:
        raise SystemExit(f"{policy}: invalid placement: {problems[0]}")
    return placement.stats.ratio, placement.stats.seconds


def print_table(rows: Sequence[dict[str, object]]) -> None:
    """Rows of {"instance": str, "blocks": int, "<policy>": (ratio, seconds), ...}: one line
    per instance with ratio and milliseconds per policy, then the mean ratio per policy and
    group (rows may carry a "group" key)."""
    labels = [k for k in rows[0] if k not in ("instance", "blocks", "group")] if rows else []
    head = f"{'instance':<16}{'blocks':>7}" + "".join(f"{label:>22}" for label in labels)
    print(head)
    print("-" * len(head))
    for row in rows:
        cells = "".join(f"{row[label][0]:>10.3f}x {row[label][1] * 1000:>8.1f}ms" for label in labels)  # type: ignore[index]
        print(f"{row['instance']!s:<16}{row['blocks']!s:>7}{cells}")
    print("-" * len(head))
    groups = sorted({str(row.get("group", "all")) for row in rows})
    for group in groups:
        members = [row for row in rows if str(row.get("group", "all")) == group]
        means = []
        for label in labels:
            ratios = [row[label][0] for row in members]  # type: ignore[index]
            times = [row[label][1] for row in members]  # type: ignore[index]
            means.append(f"{sum(ratios) / len(ratios):>10.3f}x {1000 * max(times):>6.1f}ms^")
        print(f"{'mean ' + group:<16}{len(members):>7}" + "".join(f"{m:>22}" for m in means))
    print("(per row: peak / lower bound, then wall time; 'mean' rows: mean ratio, ^ = slowest)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="fewer random instances")
    parser.add_argument("--only", help="comma-separated policy labels to run")
    parser.add_argument("--aliased-budgets", help="comma-separated extra budgets (s) for aliased@S columns")
    args = parser.parse_args()
    extra = [(f"aliased@{b}s", "aliased", float(b)) for b in args.aliased_budgets.split(",")] if args.aliased_budgets else []
    chosen = [p for p in POLICIES + extra if not args.only or p[0] in args.only.split(",")]
    rows = []
    for group, name, blocks in instances(args.quick):
        row: dict[str, object] = {"group": group, "instance": name, "blocks": len(blocks)}
        for label, policy, budget in chosen:
            row[label] = measure(blocks, policy, budget)
        rows.append(row)
        print(f"  done {name}", file=sys.stderr, flush=True)
    print_table(rows)
    print()
    print_graph_savings()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
