"""``rgraph sweep G --knob name=v1,v2 ... -o DIR``: what accuracy costs in GPU time."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rgraph.commands.common import add_graph_arguments, parse_params, parse_size
from rgraph.commands.outputs import warmup_seconds
from rgraph.errors import RGraphError
from rgraph.vk.instance import validation_summary

PLOT_METRICS = ("flip", "ssim", "psnr", "hdr_flip", "hdr_rel_mse", "hdr_log_psnr")


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "sweep", help="render quality-knob settings; GPU time per pass and error against a reference",
        description="Renders every setting (each knob alone from the defaults, or --grid), times each pass "
                    "(median of --frames) and compares each image with the reference setting "
                    "(defaults overridden by every --reference). Writes sweep.csv, sweep.md, "
                    "pareto_<knob>.png, images/ and errors/ into -o DIR.")
    add_graph_arguments(parser)
    parser.add_argument("--knob", action="append", metavar="NAME=V1,V2,...", required=True,
                        help="a graph param and the values to try (repeatable)")
    parser.add_argument("--reference", action="append", metavar="NAME=VALUE",
                        help="param of the reference setting (repeatable; default: the graph's defaults)")
    parser.add_argument("--grid", action="store_true", help="every combination of the knobs' values")
    parser.add_argument("--frames", type=int, default=8, help="frames per setting; times are medians (default 8)")
    parser.add_argument("--warmup", type=warmup_seconds, default=None, metavar="SECONDS",
                        help="untimed frames before each setting's timed ones: SECONDS x 200 frames, the same count for "
                             "every setting (animated scenes move by frame) (default: 0.3 s = 60 frames on a GPU, "
                             "none on a CPU device)")
    parser.add_argument("--device", type=int, default=None, help="physical device index")
    parser.add_argument("--policy", help="memory placement policy (see rgraph compile)")
    parser.add_argument("--hdr", metavar="RESOURCE",
                        help="also read back this intermediate image (kept as an extra output) for HDR metrics")
    parser.add_argument("--metric", choices=PLOT_METRICS,
                        help="error shown in the Pareto plots (default: flip, else ssim)")
    parser.add_argument("--validate", action="store_true",
                        help="run every setting under Khronos validation + syncval; exit 1 on any message")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="render the settings in N local worker processes, one process per setting")
    where.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                       help="every setting a Ray task in its own worker process (one GPU each on a GPU "
                            "cluster); ADDRESS of a running cluster, else RAY_ADDRESS or a new local one "
                            "(pip install 'rgraph[ray]')")
    parser.add_argument("--per-worker", type=int, default=1, metavar="K",
                        help="with --workers: settings one worker process renders on one device before a "
                             "fresh process takes its place (default 1)")
    parser.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    parser.add_argument("-o", "--out", type=Path, required=True, help="output folder")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from rgraph.sweep.parallel import make_executor
    from rgraph.sweep.runner import SweepRequest, run_sweep
    from rgraph.sweep.settings import parse_assignments, parse_knob
    from rgraph.sweep.writers import write_sweep
    from rgraph.vk.errors import ExecutionError, VulkanUnavailable

    if args.frames < 1:
        raise RGraphError.in_file("<command line>", f"--frames must be at least 1, got {args.frames}")
    request = SweepRequest(
        graph=args.graph, knobs=[parse_knob(k) for k in args.knob], scene=args.scene,
        base=parse_params(args.param), reference=parse_assignments(args.reference, "--reference"),
        grid=args.grid, size=parse_size(args.size), frames=args.frames, warmup_s=args.warmup, device=args.device,
        policy=args.policy, hdr=args.hdr, validate=args.validate)
    if args.workers is not None and args.workers < 1:
        raise RGraphError.in_file("<command line>", f"--workers must be at least 1, got {args.workers}")
    if args.per_worker < 1:
        raise RGraphError.in_file("<command line>", f"--per-worker must be at least 1, got {args.per_worker}")
    try:
        executor = make_executor(args.workers, args.ray, use_ray=args.ray is not None,
                                 tasks_per_worker=args.per_worker)
    except ImportError:
        print("rgraph: error: --ray needs Ray: pip install 'rgraph[ray]'", file=sys.stderr)
        return 2
    try:
        result = run_sweep(request, args.out, progress=args.progress and sys.stderr.isatty(), executor=executor)
    except (VulkanUnavailable, ExecutionError) as exc:
        print(f"rgraph: error: {exc}", file=sys.stderr)
        return 2
    finally:
        if executor is not None:
            executor.close()
    written, _ = write_sweep(result, args.out, args.metric)
    for line in result.notes:
        print(f"rgraph: note: {line}", file=sys.stderr)
    messages = result.messages()
    for label, message in messages:
        print(f"{label}: {message}", file=sys.stderr)
    where = f" in {executor.description}" if executor is not None else ""
    print(f"rgraph: {len(result.rows)} settings ({result.renderings} renderings) on {result.device}{where}; "
          f"wrote {written['csv']}, {written['md']} and {len(written) - 2} plot(s)", file=sys.stderr)
    for label, why in result.failures.items():
        print(f"rgraph: error: setting {label} failed: {why}", file=sys.stderr)
    if args.validate:
        print(validation_summary(len(messages)), file=sys.stderr)
    return 1 if result.failures or (args.validate and messages) else 0
