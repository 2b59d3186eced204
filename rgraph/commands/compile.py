"""``rgraph compile G ... [-o plan.json]``: write the plan (stdout without -o)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rgraph.commands.common import add_compile_arguments, add_graph_arguments, compile_from_args


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("compile", help="compile a graph into a plan JSON")
    add_graph_arguments(parser)
    add_compile_arguments(parser)
    parser.add_argument("-o", "--output", help="plan file to write (default: stdout)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.plan import dump

    text = dump(compile_from_args(args))
    if args.output:
        Path(args.output).write_text(text)
        print(f"wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0
