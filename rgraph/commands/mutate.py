"""``rgraph mutate G``: mutate each barrier of the compiled plan and report which oracle catches it.

Mutants: drop the barrier, empty its src access, narrow its dst stages (rgraph.mutate).
Oracles: check (independent replay), syncval (validation + synchronization validation),
data (readback against the CPU simulation). Exit 0 once the report is written, 2 on bad input
or when Vulkan is needed and unavailable.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rgraph.commands.common import add_graph_arguments, parse_params, parse_size
from rgraph.errors import RGraphError


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("mutate", help="mutate every barrier of a compiled graph and report which oracle "
                                           "catches each mutant")
    add_graph_arguments(parser)
    parser.add_argument("--policy", help="memory placement policy (see rgraph compile)")
    parser.add_argument("--oracles", default="check,syncval,data",
                        help="comma-separated subset of check,syncval,data (default: all three)")
    parser.add_argument("--kinds", default="drop,src-access,dst-stages",
                        help="comma-separated subset of drop,src-access,dst-stages (default: all)")
    parser.add_argument("--frames", type=int, default=2, help="frames per execution (default 2)")
    parser.add_argument("--device", type=int, default=None, help="physical device index")
    parser.add_argument("--json", type=Path, metavar="OUT", help="write the results as JSON")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    parser.set_defaults(func=run)


def _choices(text: str, allowed: tuple[str, ...], option: str) -> list[str]:
    items = [t.strip() for t in text.split(",") if t.strip()]
    bad = [t for t in items if t not in allowed]
    if bad or not items:
        raise RGraphError.in_file("<command line>", f"{option} expects a comma-separated subset of "
                                                    f"{','.join(allowed)}, got '{text}'")
    return items


def _compile(args: argparse.Namespace, gpu) -> dict:
    """The plan; sized by ``gpu`` (the device the mutants run on) when there is one."""
    from rgraph.compiler.pipeline import compile_graph

    return compile_graph(args.graph, scene_path=args.scene, params=parse_params(args.param),
                         size=parse_size(args.size), policy=args.policy,
                         memory=gpu.memory_requirements() if gpu is not None else None)


def print_report(report, out=sys.stdout) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console(file=out, width=160)
    base = report.baseline
    if base is not None:
        flags = base.caught_by
        state = "clean" if not flags else f"NOT CLEAN ({', '.join(flags)}): mutation results are unreliable"
        if base.check_error:
            state += " (check could not read it)"
        console.print(f"baseline plan: {state}")
    for o in report.check_errors()[:3]:
        console.print(f"check could not read the plan of {o.mutant.name}: {o.check_error}")
    table = Table(title=f"mutants of {report.plan.get('graph')} {report.plan.get('size')} "
                        f"(oracles: {', '.join(report.oracles)}; device: {report.device or '-'})")
    table.add_column("#", justify="right")
    table.add_column("mutant")
    table.add_column("change")
    table.add_column("caught by")
    table.add_column("evidence / explanation", overflow="fold")
    for n, o in enumerate(report.outcomes):
        evidence = []
        if o.hazards:
            evidence.append("check: " + ",".join(o.hazards))
        if o.messages:
            evidence.append("vvl: " + ",".join(o.messages[:2]) + ("..." if len(o.messages) > 2 else ""))
        if o.data_ok is False:
            evidence.append("data mismatch")
        if o.check_error:
            evidence.append("check error")
        if o.error:
            evidence.append(o.error[:80])
        if o.runtime_blind_spot:
            evidence.append(f"runtime blind spot: {o.runtime_blind_spot}")
        if o.explanation:
            evidence.append(f"UNCAUGHT: {o.explanation}")
        table.add_row(str(n), o.mutant.name, o.mutant.detail, ", ".join(o.caught_by) or "-", "; ".join(evidence))
    console.print(table)
    for kind, (caught, total) in report.summary().items():
        console.print(f"{kind}: {caught}/{total} caught")
    per_oracle = {o: sum(o in r.caught_by for r in report.outcomes) for o in report.oracles}
    console.print("caught per oracle: " + ", ".join(f"{k} {v}/{len(report.outcomes)}" for k, v in per_oracle.items()))
    unexplained = report.unexplained()
    console.print(f"uncaught: {len(report.uncaught())} ({len(unexplained)} unexplained); "
                  f"{report.seconds:.1f} s")


def _without_crashing_layer(plan: dict, oracles: list[str]) -> list[str]:
    """``oracles`` without syncval when the installed layer cannot create the plan's ray
    tracing pipelines (rgraph.vk.probe_rt.refuse_layer_for_ray_tracing); says so on stderr."""
    if "syncval" not in oracles:
        return oracles
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.probe_rt import refuse_layer_for_ray_tracing

    try:
        refuse_layer_for_ray_tracing(plan)
    except ExecutionError as exc:
        print(f"rgraph: note: syncval oracle off: {str(exc).removeprefix('--validate: ')}", file=sys.stderr)
        return [o for o in oracles if o != "syncval"]
    return oracles


def run(args: argparse.Namespace) -> int:
    from rgraph.mutate import KINDS, ORACLES, mutation_report
    from rgraph.vk.errors import ExecutionError, VulkanUnavailable

    oracles = _choices(args.oracles, ORACLES, "--oracles")
    kinds = _choices(args.kinds, KINDS, "--kinds")
    if args.frames < 1:
        raise RGraphError.in_file("<command line>", "--frames must be at least 1")
    runtime = bool({"syncval", "data"} & set(oracles))

    def progress(n: int, total: int, outcome) -> None:
        if not args.quiet:
            print(f"[{n}/{total}] {outcome.mutant.name}: {', '.join(outcome.caught_by) or 'uncaught'}",
                  file=sys.stderr)

    from contextlib import ExitStack

    from rgraph.api import open_device

    try:
        with ExitStack() as stack:  # one device: it sizes the plan and runs every mutant
            gpu = (stack.enter_context(open_device(validate="syncval" in oracles, device=args.device,
                                                   verbose=False)) if runtime else None)
            plan = _compile(args, gpu)
            kept = _without_crashing_layer(plan, oracles)
            if gpu is not None and kept != oracles:  # the same device without the crashing layer
                gpu.close()
                gpu = stack.enter_context(open_device(validate=False, device=args.device, verbose=False))
            oracles = kept
            report = mutation_report(plan, oracles=oracles, kinds=kinds, frames=args.frames,
                                     device_index=args.device, progress=progress, gpu=gpu)
    except (VulkanUnavailable, ExecutionError) as exc:
        print(f"rgraph: error: {exc}", file=sys.stderr)
        return 2
    base = report.baseline
    if base is not None and base.error is not None:
        print(f"rgraph: error: the unmutated plan fails, so no mutant was run (every pass runs as the "
              f"probe): {base.error}", file=sys.stderr)
        return 1
    print_report(report)
    if args.json:
        args.json.write_text(json.dumps(report.as_json(), indent=1) + "\n")
        print(f"rgraph: wrote {args.json}", file=sys.stderr)
    return 1 if base is not None and base.caught_by else 0
