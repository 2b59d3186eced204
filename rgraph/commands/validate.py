"""``rgraph validate G [--scene S]``: schema and semantic checks, nothing else."""

from __future__ import annotations

import argparse

from rgraph.commands.common import add_graph_arguments, parse_params, parse_size
from rgraph.errors import escape, quote


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("validate", help="check a graph file (and scene) for errors")
    add_graph_arguments(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.compiler.pipeline import frontend
    from rgraph.ir.cull import cull

    front = frontend(args.graph, args.scene, parse_params(args.param), parse_size(args.size))
    culling = cull(front.spec)
    scene = f" with scene {quote(front.scene.name)}" if front.scene else ""
    print(
        f"{escape(str(front.source.path))}: ok: graph {quote(front.spec.name)}{scene}: {len(culling.passes)} passes run, "
        f"{len(culling.culled)} culled, {len(front.spec.resources)} resources"
    )
    return 0
