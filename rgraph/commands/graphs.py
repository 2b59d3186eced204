"""``rgraph graphs``: list the bundled graphs (usable by name)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("graphs", help="list the bundled graphs")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.resources import bundled_graphs
    from rgraph.spec.loader import load_graph

    for name, path in bundled_graphs().items():
        source = load_graph(path)
        print(f"{name:<16} {len(source.passes):>3} passes  {source.description or ''}  ({path})")
    return 0
