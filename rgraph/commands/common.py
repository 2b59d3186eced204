"""Arguments shared by the commands that compile a graph."""

from __future__ import annotations

import argparse
import re
from typing import TYPE_CHECKING

from rgraph.errors import RGraphError

if TYPE_CHECKING:
    from rgraph.plan import Plan

_SIZE = re.compile(r"^(\d+)x(\d+)$")


def parse_size(text: str) -> tuple[int, int]:
    match = _SIZE.match(text.strip().lower())
    if not match or not 0 < int(match.group(1)) <= 16384 or not 0 < int(match.group(2)) <= 16384:
        raise RGraphError.in_file("<command line>", f"--size expects WIDTHxHEIGHT (1..16384), got '{text}'")
    return int(match.group(1)), int(match.group(2))


def parse_params(items: list[str] | None) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise RGraphError.in_file("<command line>", f"-p expects name=value, got '{item}'")
        out[name.strip()] = value.strip()
    return out


def default_size_text() -> str:
    """The one default output size of every command (``rgraph.defaults.DEFAULT_SIZE``)."""
    from rgraph.defaults import DEFAULT_SIZE

    return f"{DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]}"


def add_graph_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("graph", help="graph file, or the name of a bundled graph (rgraph graphs)")
    parser.add_argument("--scene", help="scene file (default: the graph's own 'scene:', else every feature present)")
    parser.add_argument("-p", "--param", action="append", metavar="NAME=VALUE", help="override a graph param")
    size = default_size_text()
    parser.add_argument("--size", default=size, metavar="WxH", help=f"output size (default {size})")
    parser.add_argument("--camera", type=int, default=0, help="camera preset N of the scene's 'cameras' (default 0)")
    add_outside_argument(parser)


def add_outside_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--allow-include-outside", action="store_true",
                        help="let includes, the graph's 'scene:' and a plan's scene_source name files outside "
                             "the graph's (or plan's) folder tree")


def add_compile_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--policy", help="memory placement: aliased (default), dedicated, optimal, tlsf, blocks:SIZE (docs/memory.md)")
    parser.add_argument("--profile", help="device profile (bundled name or JSON path) for sizes and alignments")
    add_sync_argument(parser)
    from rgraph.commands.multi_args import add_split_arguments

    add_split_arguments(parser)


def add_schedule_argument(parser: argparse.ArgumentParser) -> None:
    from rgraph.defaults import SCHEDULES

    parser.add_argument("--schedule", default="declaration", choices=SCHEDULES,
                        help="pass order: declaration (default: declaration order minus culled passes) or "
                             "async-early (compute/transfer-queue passes as early as dependencies allow)")


def add_sync_argument(parser: argparse.ArgumentParser) -> None:
    add_schedule_argument(parser)
    parser.add_argument("--sync", default="normal", choices=("normal", "naive"),
                        help="normal (default): the barrier generator's plan; naive: a full barrier before "
                             "every pass, all passes on the graphics queue, no semaphores (for comparison)")


def compile_from_args(args: argparse.Namespace) -> Plan:
    from rgraph.commands.multi_args import split_from_args
    from rgraph.compiler.pipeline import compile_graph_plan

    return compile_graph_plan(
        args.graph,
        scene_path=args.scene,
        params=parse_params(args.param),
        size=parse_size(args.size),
        policy=getattr(args, "policy", None),
        profile=getattr(args, "profile", None),
        sync=getattr(args, "sync", "normal"),
        split=split_from_args(args),
        schedule=getattr(args, "schedule", "declaration"),
        camera=getattr(args, "camera", 0),
    )
