"""``rgraph inspect G-or-PLAN``: human views of a plan (tables, barriers, memory, DOT, HTML).

An argument ending in ``.json`` is a plan file; anything else is a graph file or bundled
graph name, compiled first. With no view flag the summary is printed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any, TextIO

from rgraph.commands.common import default_size_text, parse_params, parse_size
from rgraph.errors import RGraphError

COMMAND_LINE = "<command line>"


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "inspect",
        help="human views of a plan",
        description="Show a compiled plan: schedule, barriers, memory, a timeline PNG, DOT, HTML.",
    )
    parser.add_argument("target", metavar="G-or-PLAN", help="plan.json, a graph file or a bundled graph name")
    parser.add_argument("--barriers", action="store_true", help="every barrier, release, wait and signal in order")
    parser.add_argument("--memory", action="store_true", help="resources, placement, heaps, culling savings")
    parser.add_argument("--timeline", metavar="OUT.png", help="draw the memory timeline (.png, .svg or .pdf)")
    parser.add_argument(
        "--dot", metavar="OUT", nargs="?", const="-",
        help="the pass graph as DOT (stdout; OUT.dot/.gv for text, OUT.svg/.pdf/.png rendered by graphviz)",
    )
    parser.add_argument("--html", metavar="OUT", help="write a self-contained HTML report")
    parser.add_argument("--lowered", action="store_true",
                        help="what the runtime will record (rgraph/vk/lower): barrier calls per pass, batches, "
                             "semaphore edges, submit order; no device needed")
    parser.add_argument("--queues", choices=("single", "separate"), default="single",
                        help="queue-family layout for --lowered: single (default: one graphics+compute+transfer "
                             "family, as on lavapipe) or separate (graphics, compute and transfer families, as on "
                             "NVIDIA)")
    parser.add_argument("--no-layer-workarounds", dest="layer_workarounds", action="store_false",
                        help="--lowered without the validation-layer 1.3.239 workarounds")
    parser.add_argument("--json", action="store_true",
                        help="print the summary (and --barriers/--memory) as JSON (docs/cli-json.md)")
    parser.add_argument("--timings", metavar="T.json",
                        help="per-pass GPU times of a run that kept the culled passes (rgraph run --timings): "
                             "shows the milliseconds culling saved")
    parser.add_argument("--scene", metavar="S", help="scene file or name (when compiling a graph)")
    parser.add_argument("-p", "--param", dest="params", metavar="K=V", action="append", default=[],
                        help="override a graph parameter (when compiling a graph)")
    parser.add_argument("--size", metavar="WxH", help=f"output size (when compiling a graph; default {default_size_text()})")
    parser.add_argument("--policy", metavar="P", help="memory placement policy (when compiling a graph)")
    parser.add_argument("--profile", metavar="D", help="device profile for memory sizes (when compiling a graph)")
    from rgraph.commands.multi_args import add_split_arguments

    add_split_arguments(parser)
    parser.set_defaults(func=run)


def obtain_plan(args: argparse.Namespace) -> dict[str, Any]:
    """Load the plan file, or compile the graph with the given scene, params, size and policy."""
    from rgraph.report.plan_file import check_plan, load_plan

    target: str = args.target
    compile_flags = [f for f in ("scene", "size", "policy", "profile", "devices", "split") if getattr(args, f, None)] + (["-p"] if args.params else [])
    if target.endswith(".json"):
        if compile_flags:
            raise RGraphError.in_file(
                COMMAND_LINE, f"{', '.join(compile_flags)} only apply when compiling a graph, not to a plan file"
            )
        return load_plan(target)
    from rgraph.compiler.pipeline import compile_graph

    options: dict[str, Any] = {"params": parse_params(args.params), "policy": args.policy}
    if args.size:
        options["size"] = parse_size(args.size)
    if args.profile:
        options["profile"] = args.profile
    from rgraph.commands.multi_args import split_from_args

    split = split_from_args(args)
    if split is not None:
        options["split"] = split
    plan = compile_graph(target, scene_path=args.scene, **options)
    check_plan(plan, target)
    return plan


def load_timings(path: str) -> dict[str, Any]:
    """A ``rgraph run --timings`` JSON file: {"device", "passes": {name: ms}, "total_ms", ...}."""
    import json

    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise RGraphError.in_file(path, f"cannot read: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise RGraphError.in_file(path, f"not JSON: {exc.msg}", exc.lineno, exc.colno) from None
    if not isinstance(data, dict) or not isinstance(data.get("passes"), dict):
        raise RGraphError.in_file(path, "not a timings file: expected an object with 'passes' (rgraph run --timings)")
    return data


def check_timings_size(plan: dict[str, Any], timings: dict[str, Any], path: str) -> None:
    """Refuse timings measured at another output size than the plan's (older files carry none)."""
    measured, planned = timings.get("size"), plan.get("size")
    if measured and planned and list(measured) != list(planned):
        raise RGraphError.in_file(
            path, f"timings were measured at {measured[0]}x{measured[1]} but the plan is {planned[0]}x{planned[1]}; "
                  f"pass --size {measured[0]}x{measured[1]} (or rerun with --size {planned[0]}x{planned[1]})")


def _write(path: str, data: str | bytes) -> None:
    try:
        if isinstance(data, bytes):
            Path(path).write_bytes(data)
        else:
            Path(path).write_text(data, encoding="utf-8")
    except OSError as exc:
        raise RGraphError.in_file(path, f"cannot write: {exc.strerror or exc}") from None


def emit_dot(plan: dict[str, Any], dest: str, out: TextIO) -> None:
    """DOT text to ``out`` (``-``) or a ``.dot``/``.gv`` file; ``.svg``/``.pdf``/``.png`` are
    rendered by graphviz; any other suffix is refused."""
    from rgraph.report.dot import RENDERED_SUFFIXES, TEXT_SUFFIXES, dot_available, dot_render, plan_to_dot

    text = plan_to_dot(plan)
    suffix = Path(dest).suffix.lower().lstrip(".")
    if dest == "-":
        out.write(text)
    elif suffix in RENDERED_SUFFIXES:
        if not dot_available():
            raise RGraphError.in_file(dest, "graphviz 'dot' is not installed; write a .dot file instead")
        try:
            _write(dest, dot_render(text, suffix))
        except RuntimeError as exc:
            raise RGraphError.in_file(dest, str(exc)) from None
    elif suffix in TEXT_SUFFIXES:
        _write(dest, text)
    else:
        known = ", ".join("." + s for s in (*TEXT_SUFFIXES, *RENDERED_SUFFIXES))
        raise RGraphError.in_file(COMMAND_LINE, f"--dot {dest}: unknown suffix; use one of {known} (or no file for stdout)")


def lowered_text(plan: Any, queues: str, workarounds: bool = True) -> str:
    """``--lowered``: the recording of ``plan`` on the ``queues`` model, as text."""
    from rgraph.vk.lower import LAYER_WORKAROUNDS, LoweringError, lower
    from rgraph.vk.lower.queues import MODELS
    from rgraph.vk.lower.text import format_recording

    try:
        recording = lower(plan, MODELS[queues](), workarounds=LAYER_WORKAROUNDS if workarounds else ())
    except LoweringError as exc:
        raise RGraphError.in_file(COMMAND_LINE, f"--lowered: {exc}") from None
    return format_recording(recording)


def _warn_if_not_runnable(path: str, err: TextIO) -> None:
    """The views show partial plans too; say when the typed loader (``rgraph run``) refuses one."""
    from rgraph.plan import load

    try:
        load(path)
    except RGraphError as exc:
        d = exc.first
        print(f"{d.location}: warning: {d.message} (rgraph run refuses this plan; the views show what is there)",
              file=err)


def run(args: argparse.Namespace, out: TextIO | None = None, err: TextIO | None = None) -> int:
    from rgraph.report import text
    from rgraph.report.table import make_console

    out = out if out is not None else sys.stdout
    err = err if err is not None else sys.stderr
    plan = obtain_plan(args)
    if args.target.endswith(".json") and not args.lowered:
        _warn_if_not_runnable(args.target, err)
    console = make_console(out)
    dot_to_stdout = args.dot == "-"
    timings = load_timings(args.timings) if args.timings else None
    if timings is not None:
        check_timings_size(plan, timings, args.timings)
    if args.lowered:  # what rgraph run would record: a plan file must pass the typed loader
        from rgraph.plan import load

        source = load(args.target) if args.target.endswith(".json") else plan
        out.write(lowered_text(source, args.queues, args.layer_workarounds))
    if args.json:
        if dot_to_stdout:
            raise RGraphError.in_file(COMMAND_LINE, "--json and --dot to stdout both print; give --dot a file")
        from rgraph.commands.jsonout import document, emit
        from rgraph.report.json_view import inspect_document

        emit(document("inspect", True, **inspect_document(plan, timings, barriers=args.barriers,
                                                           memory=args.memory)), out)
    elif not (args.barriers or args.memory or dot_to_stdout or args.lowered):
        text.print_summary(console, plan, timings)
        from rgraph.report.devices import print_devices

        print_devices(console, plan)
    if args.barriers and not args.json:
        text.print_barriers(console, plan)
    if args.memory and not args.json:
        if args.barriers:
            console.print()
        text.print_memory(console, plan, timings)
    if args.dot is not None:
        emit_dot(plan, args.dot, out)
        if not dot_to_stdout:
            print(f"wrote {args.dot}", file=err)
    if args.timeline:
        from rgraph.report.timeline import timeline_format, write_timeline_png

        try:
            timeline_format(args.timeline)
        except ValueError as exc:
            raise RGraphError.in_file(COMMAND_LINE, f"--timeline {args.timeline}: {exc}") from None
        try:
            write_timeline_png(plan, args.timeline)
        except OSError as exc:
            raise RGraphError.in_file(args.timeline, f"cannot write: {exc.strerror or exc}") from None
        print(f"wrote {args.timeline}", file=err)
    if args.html:
        from rgraph.report.html import plan_html

        _write(args.html, plan_html(plan, timings=timings))
        print(f"wrote {args.html}", file=err)
    return 0
