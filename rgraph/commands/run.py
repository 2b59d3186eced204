"""``rgraph run G-or-PLAN``: compile (sizes from the live device) and execute on Vulkan.

One instance and one device (``rgraph.open_device``) serve both: the compiler sizes resources
with the device's memory requirements, then the same device runs the plan. A plan file is
loaded through the typed loader (``rgraph.plan.load``) and replayed by the independent
checker (``rgraph.check``) first; a malformed plan or one with hazards is refused (exit 2)
unless ``--unchecked``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rgraph.commands.common import (
    add_graph_arguments,
    add_sync_argument,
    default_size_text,
    parse_params,
    parse_size,
)
from rgraph.commands.outputs import (
    check_output_file,
    check_pass_params,
    frame_count,
    output_path,
    warmup_seconds,
    write_output,
)
from rgraph.errors import RGraphError
from rgraph.vk.instance import validation_summary

if TYPE_CHECKING:
    from rgraph.plan import Plan

COMMAND_LINE = "<command line>"


class DefaultSize(str):
    """The default ``--size`` (a str subclass), so that a plan file can tell it was not given."""


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("run", help="compile and execute a graph (or a plan JSON) on a Vulkan device")
    add_graph_arguments(parser)
    parser.set_defaults(size=DefaultSize(default_size_text()))  # a plan file has its own size
    parser.add_argument("--policy", help="memory placement policy (see rgraph compile)")
    add_sync_argument(parser)
    parser.add_argument("--frames", type=frame_count, default=1, help="frames to run (default 1)")
    parser.add_argument("--warmup", type=warmup_seconds, default=None, metavar="SECONDS",
                        help="untimed frames before the timed ones (default: 0.3 s on a GPU, none on a CPU device)")
    parser.add_argument("--validate", action="store_true",
                        help="Khronos validation + synchronization validation; exit 1 on any message")
    parser.add_argument("--check-data", dest="check_data", action=argparse.BooleanOptionalAction, default=None,
                        help="compare outputs with the probe's CPU simulation (default: on with --validate)")
    parser.add_argument("--out", type=output_path,
                        help="write the first output image as PNG (a rendered float image clamped to [0, 1] as stored)")
    parser.add_argument("--timings", type=output_path,
                        help="write per-pass GPU times as JSON (median ms; start/end within the frame per queue)")
    parser.add_argument("--heatmap", type=output_path,
                        help="write the output image light_heat (lights shaded per pixel: graphs/clustered.yaml) as PNG")
    parser.add_argument("--trace", type=output_path, metavar="OUT.json",
                        help="write the frame in the Chrome trace event format (Perfetto, chrome://tracing): "
                             "a track per queue, passes as slices, barriers, semaphore waits as flows")
    parser.add_argument("--logic-hz", dest="logic_hz", type=logic_rate, default=None, metavar="HZ",
                        help="run the scene's logic (deformation, animation) on its own thread at HZ; frames "
                             "are submitted as fast as they complete, interpolating between the last two logic "
                             "states (reports the render thread's CPU per frame)")
    parser.add_argument("--device", type=int, default=None, help="physical device index")
    parser.add_argument("--naive-cpu", dest="naive_cpu", action="store_true",
                        help="draw the scene the engines' way for comparison: per-object CPU frustum culling and "
                             "one draw call per object (-p draw.mode=naive; the graph must have that param)")
    parser.add_argument("--json", action="store_true",
                        help="print the result (timings, validation messages, data check) as JSON (docs/cli-json.md)")
    parser.add_argument("--unchecked", action="store_true",
                        help="run a plan file even if rgraph check finds hazards in it")
    parser.add_argument("--no-layer-workarounds", dest="layer_workarounds", action="store_false",
                        help="record the plan without the validation-layer 1.3.239 workarounds "
                             "(rgraph/vk/lower/workarounds; validation messages are then reported, not avoided)")
    from rgraph.commands.multi_args import add_split_arguments

    add_split_arguments(parser, indices=True)
    parser.set_defaults(func=run)


def logic_rate(text: str) -> float:
    """``--logic-hz``: a positive, finite number of ticks per second."""
    try:
        hz = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0 < hz <= 10_000):
        raise argparse.ArgumentTypeError(f"must be in (0, 10000] Hz, not {text}")
    return hz


def rest_pose_note(plan: dict) -> str | None:
    """A line when the plan traces rays against a scene with skinned meshes: acceleration
    structures hold them in their rest pose (docs/raytracing.md), though raster passes animate them."""
    if not plan.get("scene_source") or not any(
            r["kind"] == "accel" and r.get("accel", {}).get("geometry") == "scene" for r in plan["resources"]):
        return None
    from rgraph.spec.scene import load_scene

    skinned = sum(1 for m in load_scene(plan["scene_source"]).model.meshes if m.skinned is not None)
    if not skinned:
        return None
    return (f"rgraph: note: the scene's {skinned} skinned mesh(es) are traced in their rest pose "
            "(acceleration structures do not follow skinning)")


def uniform_range_note(plan: dict, max_uniform_range: int) -> str | None:
    """A warning when a pass reads a buffer larger than ``maxUniformBufferRange`` as
    ``uniform``: one descriptor binds only that much of it (forward shades the first
    1,024 lights of a larger ``lights`` buffer; the clustered graphs read it as storage)."""
    sizes = {r["name"]: int(r.get("bytes") or 0) for r in plan["resources"] if r["kind"] == "buffer"}
    over = [(p["name"], a["resource"]) for p in plan["passes"] for a in p["accesses"]
            if a["usage"] == "uniform" and sizes.get(a["resource"], 0) > max_uniform_range]
    if not over:
        return None
    name, res = over[0]
    return (f"rgraph: warning: pass {name!r} reads buffer {res!r} ({sizes[res]:,} bytes) as a uniform buffer; "
            f"the device binds its first {max_uniform_range:,} bytes (maxUniformBufferRange)"
            + (" and the rest is not read" if name != "forward" or res != "lights" else
               f": {max_uniform_range // 64:,} of {sizes[res] // 64:,} lights are shaded "
               "(graphs/surgery_clustered.yaml shades any count)"))


def render_thread_line(timings: dict) -> str:
    """One stderr line: the render thread's CPU per frame, and the logic thread's ticks."""
    r = timings.get("render_thread") or {}
    line = (f"rgraph: render thread {r.get('cpu_us_per_frame', 0.0):.1f} us CPU per frame "
            f"(host updates {r.get('update_us', 0.0):.1f} us median)")
    logic = timings.get("logic")
    if logic:
        measured = logic.get("measured_hz")
        line += (f"; logic {logic['ticks']} ticks at {logic['hz']:g} Hz"
                 + (f" (measured {measured:.1f} Hz" if measured else " (")
                 + f", {logic['late_ticks']} late, {logic.get('behind_at_stop', 0)} behind at stop)")
        skin = logic.get("skin") or {}
        if skin.get("worker") == "process" and skin.get("tick_us") is not None:
            line += (f"; skinning in a worker process: {skin['tick_us'] / 1e3:.1f} ms per state, the logic "
                     f"thread waits {skin['wait_us'] / 1e3:.2f} ms")
    return line


def is_plan_file(target: str) -> bool:
    path = Path(target)
    return path.suffix == ".json" and path.is_file()


def load_checked_plan(path: Path, *, unchecked: bool = False) -> dict:
    """:func:`load_checked_model` as a plan document."""
    from rgraph.plan import to_json_dict

    return to_json_dict(load_checked_model(path, unchecked=unchecked))


def load_checked_model(path: Path, *, unchecked: bool = False) -> Plan:
    """A plan file through the typed loader (malformed: ``RGraphError``, one located line),
    then replayed by ``rgraph.check``: hazards are refused (``RGraphError``) unless ``unchecked``."""
    from rgraph.plan import load, to_json_dict

    model = load(path)
    if model.format != "rgraph-plan/1":
        raise RGraphError.in_file(path, "not an rgraph plan (format != rgraph-plan/1)")
    from rgraph.spec.paths import check_plan_scene

    check_plan_scene(to_json_dict(model), Path(path))
    if not unchecked:
        from rgraph.check import check_file

        _checked, hazards = check_file(path)
        if hazards:
            first = hazards[0].message.splitlines()[0]
            raise RGraphError.in_file(
                path, f"rgraph check finds {len(hazards)} hazard{'s' if len(hazards) != 1 else ''} in this plan "
                      f"(first: {first}); see 'rgraph check {path}', or pass --unchecked to run it anyway")
    return model


def refuse_compile_flags(args: argparse.Namespace, *, multi: bool = False) -> None:
    """Flags that only shape a compile are errors with a plan file (it was compiled with its
    own); a multi-device plan also has its own split and synchronization."""
    flags = [("--size", not isinstance(args.size, DefaultSize)), ("--scene", args.scene), ("-p", args.param),
             ("--policy", args.policy), ("--schedule", args.schedule != "declaration"), ("--camera", args.camera)]
    if multi:
        flags += [("--split", args.split), ("--balance", args.balance != "static"), ("--sync", args.sync != "normal")]
    given = [flag for flag, value in flags if value]
    if given:
        verb = "applies" if len(given) == 1 else "apply"
        raise RGraphError.in_file(COMMAND_LINE, f"{', '.join(given)} only {verb} when compiling a graph, not to "
                                                f"a plan file (its size is {_plan_size(args.graph)})")


def _plan_from_file(args: argparse.Namespace) -> dict:
    refuse_compile_flags(args)
    plan = load_checked_plan(Path(args.graph), unchecked=args.unchecked)
    if args.sync == "naive" and plan.get("stats", {}).get("sync") != "naive":
        from rgraph.compiler.pipeline import apply_sync_mode

        plan = apply_sync_mode(plan, "naive")
    return plan


def _params_view(args: argparse.Namespace) -> dict:
    """The passes' impls and params as a plan would carry them, without touching a device;
    every ``impl`` must name a registered implementation (located in the graph, as validate)."""
    from rgraph.commands.outputs import params_view
    from rgraph.commands.validate import check_impls
    from rgraph.compiler.pipeline import frontend

    front = frontend(args.graph, args.scene, parse_params(args.param), parse_size(args.size))
    check_impls(front.source)
    return params_view(front.spec, args.graph)


def _has_param(graph: str, name: str) -> bool:
    """Whether ``graph`` (a file or bundled name) declares param ``name``; a graph that does not
    load answers True, so the usual located error reports it."""
    from rgraph.resources import resolve_graph
    from rgraph.spec.loader import load_graph

    try:
        return name in load_graph(resolve_graph(graph)).params
    except RGraphError:
        return True


def _is_multi_plan(target: str) -> bool:
    try:
        return is_plan_file(target) and bool(json.loads(Path(target).read_text()).get("multi_device"))
    except (OSError, ValueError):
        return False


def _plan_size(path: str) -> str:
    try:
        size = json.loads(Path(path).read_text()).get("size")
        return f"{size[0]}x{size[1]}"
    except Exception:  # noqa: BLE001 -- only for the message
        return "fixed"


def _print_table(plan: dict, timings: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"GPU time per pass (median of {timings.get('frames')} frames)")
    table.add_column("#", justify="right")
    table.add_column("pass")
    table.add_column("queue")
    table.add_column("kind")
    table.add_column("ms", justify="right")
    for p in plan["passes"]:
        ms = timings["passes"].get(p["name"])
        table.add_row(str(p["index"]), p["name"], p["queue"], p["kind"], "-" if ms is None else f"{ms:.3f}")
    total = timings.get("total_ms")
    table.add_row("", "frame", "", "", "-" if total is None else f"{total:.3f}")
    Console(stderr=True).print(table)


def _status(args: argparse.Namespace, result) -> int:
    failed = (args.validate and result.messages) or result.data_ok is False
    return 1 if failed else 0


def _json(args: argparse.Namespace, plan: dict, result) -> int:
    from rgraph.commands.jsonout import document, emit

    status = _status(args, result)
    emit(document(
        "run", status == 0, graph=plan.get("graph"), device=result.device_name, size=plan.get("size"),
        frames=args.frames, timings=result.timings, culled=plan.get("culled") or [],
        validation={"enabled": bool(args.validate), "messages": [str(m) for m in result.messages]},
        data_check=None if result.data_ok is None else {
            "ok": bool(result.data_ok), "mismatches": [str(m) for m in result.mismatches],
            "unpredictable": [str(u) for u in result.unchecked]},
        out=str(args.out) if args.out else None))
    return status


def _report_clusters(args: argparse.Namespace, outputs: dict) -> None:
    """Light-list statistics and the heatmap of a clustered graph (rgraph.passes.cluster_report)."""
    if "cluster_stats" not in outputs and not args.heatmap:
        return
    from rgraph.resources import builtin_passes

    cluster_report = importlib.import_module(f"{builtin_passes().__name__}.cluster_report")

    if "cluster_stats" in outputs:
        print(cluster_report.stats_line(cluster_report.stats_of(outputs["cluster_stats"])), file=sys.stderr)
    if args.heatmap:
        print(cluster_report.write_heatmap(args.heatmap, outputs["light_heat"][..., 0]), file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    from rgraph.api import open_device
    from rgraph.vk.errors import ExecutionError, VulkanUnavailable
    from rgraph.vk.lower import LAYER_WORKAROUNDS

    if args.frames < 1:
        print("rgraph: error: --frames must be at least 1", file=sys.stderr)
        return 2
    if getattr(args, "naive_cpu", False):
        if is_plan_file(args.graph):
            raise RGraphError.in_file("<command line>", "--naive-cpu (-p draw.mode=naive) only applies when "
                                                        "compiling a graph, not to a plan file")
        if not _has_param(args.graph, "draw.mode"):
            raise RGraphError.in_file("<command line>", f"--naive-cpu needs a graph with param 'draw.mode' "
                                                        f"(graphs/clustered.yaml); {args.graph} has none")
        args.param = [*(args.param or []), "draw.mode=naive"]
    for flag, target in (("--out", args.out), ("--timings", args.timings), ("--trace", args.trace),
                         ("--heatmap", args.heatmap)):
        if target is not None:
            check_output_file(target, flag)
    if not Path(args.graph).suffix == ".json":  # params first: compiling for the device opens it
        check_pass_params(_params_view(args), parse_params(args.param))
    from rgraph.commands.multi_args import device_list

    devices = device_list(args)
    if devices is not None and (len(devices) > 1 or _is_multi_plan(args.graph)):
        from rgraph.commands.run_multi import run_multi

        checked = None
        if is_plan_file(args.graph):  # as a one-device plan file: its own compile, checked first
            refuse_compile_flags(args, multi=True)
            checked = load_checked_model(Path(args.graph), unchecked=args.unchecked)
        return run_multi(args, devices, default_size_text(), checked)
    if devices is not None and args.device is None:
        args.device = devices[0]
    plan = _plan_from_file(args) if is_plan_file(args.graph) else None
    try:
        with open_device(validate=args.validate, device=args.device) as gpu:
            if plan is None:
                from rgraph.compiler.pipeline import compile_graph

                plan = compile_graph(args.graph, scene_path=args.scene, params=parse_params(args.param),
                                     size=parse_size(args.size), policy=args.policy,
                                     sync=args.sync, schedule=args.schedule, camera=args.camera,
                                     memory=gpu.memory_requirements())
            check_pass_params(plan, parse_params(args.param))
            outputs = {r["name"] for r in plan["resources"] if r["lifetime"] == "output"}
            if args.heatmap and "light_heat" not in outputs:
                raise RGraphError.in_file(args.graph, "--heatmap needs an output image 'light_heat' "
                                                      "(see graphs/clustered.yaml)")
            exe = gpu.load(plan, workarounds=LAYER_WORKAROUNDS if args.layer_workarounds else (),
                           logic_hz=args.logic_hz)
            result = exe.run_and_check(args.frames, check_data=args.validate if args.check_data is None
                                       else args.check_data, out_png=args.out, warmup_s=args.warmup,
                                       read_outputs=bool(args.heatmap) or "cluster_stats" in outputs)
            uniform_note = uniform_range_note(plan, int(gpu.device.properties.limits.maxUniformBufferRange))
            result.messages = gpu.close()  # the device's teardown included
    except (VulkanUnavailable, ExecutionError) as exc:
        if args.json:
            from rgraph.commands.jsonout import diagnostic, document, emit
            from rgraph.errors import Location

            emit(document("run", False, [diagnostic("error", Location("<device>"), str(exc))]))
            return 2
        print(f"rgraph: error: {exc}", file=sys.stderr)
        return 2
    _report_clusters(args, result.outputs)
    if args.timings:
        write_output(args.timings, json.dumps({"device": result.device_name, "size": plan.get("size"),
                                               **result.timings}, indent=1, sort_keys=True) + "\n", "--timings")
    if args.trace:
        from rgraph.report.trace import chrome_trace

        trace = chrome_trace(plan, {"device": result.device_name, **result.timings})
        write_output(args.trace, json.dumps(trace, indent=None, sort_keys=True) + "\n", "--trace")
    if args.json:
        return _json(args, plan, result)
    if plan["passes"]:
        _print_table(plan, result.timings)
    else:
        print("rgraph: nothing to execute: every pass was culled", file=sys.stderr)
    for entry in plan.get("culled", []):
        print(f"rgraph: culled {entry['pass']}: {entry['reason']}", file=sys.stderr)
    for note in (rest_pose_note(plan), uniform_note):
        if note:
            print(note, file=sys.stderr)
    status = 0
    for message in result.messages:
        print(str(message), file=sys.stderr)
    if not args.layer_workarounds:
        print("rgraph: recorded without the validation-layer workarounds", file=sys.stderr)
    if args.validate:
        print(validation_summary(len(result.messages)), file=sys.stderr)
        if result.messages:
            status = 1
    print(render_thread_line(result.timings), file=sys.stderr)
    if result.data_ok is not None:
        for mismatch in result.mismatches:
            print(f"rgraph: data mismatch: {mismatch}", file=sys.stderr)
        note = f" ({len(result.unchecked)} subresource(s) not predictable)" if result.unchecked else ""
        print(f"rgraph: data check {'ok' if result.data_ok else 'FAILED'}{note}", file=sys.stderr)
        if not result.data_ok:
            status = 1
    if args.out:
        print(f"rgraph: wrote {args.out}", file=sys.stderr)
    return status
