"""``rgraph place TRACE.csv [--policy P]``: place a MiniMalloc trace and print the peak."""

from __future__ import annotations

import argparse

from rgraph.errors import RGraphError


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "place",
        help="place a lifetime trace (MiniMalloc CSV) under a memory policy",
        description="Place a MiniMalloc CSV trace (id,lower,upper,size; upper exclusive) and "
        "print peak bytes, the lower bound and their ratio.",
    )
    parser.add_argument("trace", help="CSV trace: id,lower,upper,size[,alignment]")
    parser.add_argument("--policy", default="aliased", help="dedicated | aliased | optimal | tlsf | blocks:SIZE")
    parser.add_argument("--budget", type=float, default=None,
                        help="time budget in seconds (default: 1 for aliased, 2 for optimal; the compiler uses 0.05)")
    parser.add_argument("--verify", action="store_true", help="check the placement independently")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.memory import TRACE_BUDGET_S, parse_place_args, place
    from rgraph.memory.trace import read_trace
    from rgraph.memory.verify import overlaps

    policy, budget = parse_place_args(args.policy, args.budget, source="--policy")
    if budget is None and policy.kind == "aliased":
        budget = TRACE_BUDGET_S
    blocks = read_trace(args.trace)
    placement = place(blocks, policy, **({"time_budget_s": budget} if budget is not None else {}))
    s = placement.stats
    print(
        f"policy={s.policy} blocks={len(blocks)} peak={s.peak_bytes} lower_bound={s.lower_bound_bytes} "
        f"ratio={s.ratio:.4f} unaliased={s.unaliased_bytes} allocations={s.allocations} "
        f"seconds={s.seconds:.3f}"
    )
    if args.verify:
        problems = overlaps(blocks, placement)
        for problem in problems:
            print(f"overlap: {problem}")
        if problems:
            raise RGraphError.in_file(args.trace, f"placement has {len(problems)} problems")
        print("verified: no overlaps, offsets aligned")
    return 0
