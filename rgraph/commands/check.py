"""``rgraph check PLAN.json``: replay a plan and report every synchronization hazard.

Exit 0 when clean, 1 when hazards were found, 2 when the file is not a readable plan.
"""

from __future__ import annotations

import argparse
from collections import Counter

from rgraph.commands.jsonout import document, emit


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "check",
        help="replay a plan with an independent happens-before model and report hazards",
        description="Replay a compiled plan (rgraph compile) with an independent happens-before "
                    "model and report every hazard: RAW/WAR/WAW, layouts, queue ownership, "
                    "semaphores, aliasing, end-of-frame state. Exit 0 clean, 1 hazards, 2 bad file.",
    )
    parser.add_argument("plan", help="plan JSON written by rgraph compile")
    parser.add_argument("--json", action="store_true", help="print the result as JSON (docs/cli-json.md)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.check import check_file

    model, hazards = check_file(args.plan)
    barriers = sum(len(p.barriers) for p in model.passes)  # plan stats.barriers, as inspect shows
    releases = sum(len(p.releases) for p in model.passes)
    if args.json:
        emit(document("check", not hazards, file=args.plan, hazards=[{
            "kind": h.kind, "pass": h.pass_index, "pass_name": h.pass_name, "resource": h.resource,
            "subresource": None if h.subresource is None else {"mips": list(h.subresource[0]),
                                                                 "layers": list(h.subresource[1])},
            "message": h.message,
        } for h in hazards], checked={"passes": len(model.passes), "barriers": barriers, "releases": releases,
                                      "resources": len(model.resources)}))
        return 1 if hazards else 0
    for h in hazards:
        print(h.message)
    rel = f" + {releases} queue-family release{'s' if releases != 1 else ''}" if releases else ""
    checked = f"{len(model.passes)} passes, {barriers} barriers{rel}, {len(model.resources)} resources"
    if hazards:
        kinds = Counter(h.kind for h in hazards)
        summary = ", ".join(f"{n} {k}" for k, n in sorted(kinds.items()))
        print(f"{args.plan}: {len(hazards)} hazard{'s' if len(hazards) != 1 else ''} ({summary}); checked {checked}")
        return 1
    print(f"{args.plan}: clean; checked {checked}")
    return 0
