"""``rgraph compile G ... [-o plan.json]``: write the plan (stdout without -o)."""

from __future__ import annotations

import argparse
import sys

from rgraph.commands.common import add_compile_arguments, add_graph_arguments, compile_from_args
from rgraph.commands.outputs import check_output_file, write_output


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("compile", help="compile a graph into a plan JSON")
    add_graph_arguments(parser)
    add_compile_arguments(parser)
    parser.add_argument("-o", "--output", help="plan file to write (default: stdout)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.plan import dumps

    if args.output:
        check_output_file(args.output, "-o")
    text = dumps(compile_from_args(args))
    if args.output:
        write_output(args.output, text, "-o")
        print(f"wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0
