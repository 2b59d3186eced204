"""``rgraph compile G ... [-o plan.json]``: write the plan (stdout without -o)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rgraph.commands.common import add_compile_arguments, add_graph_arguments, compile_from_args

if TYPE_CHECKING:
    from rgraph.plan import Plan


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("compile", help="compile a graph into a plan JSON")
    add_graph_arguments(parser)
    add_compile_arguments(parser)
    parser.add_argument("-o", "--output", help="plan file to write (default: stdout)")
    parser.add_argument("--json", action="store_true",
                        help="print a JSON summary (docs/cli-json.md); the plan goes to -o or into its 'plan' key")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.plan import dump

    plan = compile_from_args(args)
    text = dump(plan)
    if args.json:
        return _json(args, plan, text)
    if args.output:
        Path(args.output).write_text(text)
        print(f"wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _json(args: argparse.Namespace, plan: Plan, text: str) -> int:
    from rgraph.commands.jsonout import document, emit

    if args.output:
        Path(args.output).write_text(text)
    doc = plan.to_json_dict()
    body = {"file": plan.source, "graph": plan.graph, "output": args.output,
            "passes": [p.name for p in plan.passes], "culled": doc["culled"],
            "barriers": plan.barrier_count, "releases": sum(len(p.releases) for p in plan.passes),
            "stats": doc["stats"]}
    if not args.output:
        body["plan"] = doc
    emit(document("compile", True, **body))
    return 0
