"""``rgraph validate G [--scene S]``: schema and semantic checks, nothing else.

Beyond what compiling checks, ``impl`` names are looked up in the pass registry, pass params
are checked against their implementations' schemas (as ``rgraph run`` does), and buffers
that probe passes use as ``indirect`` must hold the probe's argument header. Warnings
(e.g. every pass culled) go to stderr as ``FILE:LINE:COL: warning: ...`` and keep exit 0.
"""

from __future__ import annotations

import argparse
import sys

from rgraph.commands.common import add_graph_arguments, parse_params, parse_size
from rgraph.commands.jsonout import diagnostic, document, emit
from rgraph.errors import Location, RGraphError, escape, quote


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "validate", help="check a graph file (and scene) for errors",
        description="Load, specialize and cull a graph (with its scene and params) and check pass "
                    "implementation names; nothing is compiled or run. Exit 0 ok (warnings on stderr), "
                    "2 on errors as FILE:LINE:COL: error: message.")
    add_graph_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the result as JSON (docs/cli-json.md)")
    parser.set_defaults(func=run)


def check_impls(source) -> None:
    """Every pass's ``impl`` must name a registered implementation."""
    from rgraph import impl
    from rgraph.spec.pydantic_errors import did_you_mean

    known = impl.names()
    for located in source.passes.values():
        name = located.model.impl
        if name is not None and name not in known:
            raise RGraphError.at(
                located.loc("impl"),
                f"no pass implementation named '{name}'{did_you_mean(name, known)}; "
                f"registered: {', '.join(known)} (omit impl to run the probe)")


def check_probe_buffers(source, spec) -> None:
    """An ``indirect`` buffer that a probe pass (no ``impl``) touches needs the probe's header."""
    from rgraph.probe.values import HEADER_WORDS, INDIRECT_MIN_BYTES

    passes, resources = spec.passes, spec.resources
    indirect = {a.resource for p in passes for a in p.accesses if a.usage == "indirect"}
    for name in sorted(indirect):
        probe = next((p.name for p in passes if p.impl is None and any(a.resource == name for a in p.accesses)), None)
        if probe is not None and resources[name].bytes < INDIRECT_MIN_BYTES:
            raise RGraphError.at(
                source.resources[name].loc("bytes"),
                f"buffer '{name}' is used as indirect and pass '{probe}' runs the probe (no impl), which needs "
                f"at least {INDIRECT_MIN_BYTES} bytes here ({4 * HEADER_WORDS}-byte header of draw, indexed-draw "
                f"and dispatch arguments + one value word), got {resources[name].bytes}; "
                "give the pass an impl or the buffer more bytes",
            )


def warnings(front, culling) -> list[tuple[Location, str]]:
    out = []
    if front.spec.passes and not culling.passes:
        reasons = sorted({c.reason for c in culling.culled})
        out.append((Location(str(front.source.path)),
                    f"every pass is culled ({'; '.join(reasons)}): the frame does nothing"))
    return out


def run(args: argparse.Namespace) -> int:
    from rgraph.commands.outputs import check_pass_params, params_view
    from rgraph.compiler.accel import check_geometry
    from rgraph.compiler.pipeline import frontend
    from rgraph.ir.cull import cull

    front = frontend(args.graph, args.scene, parse_params(args.param), parse_size(args.size))
    check_impls(front.source)
    check_pass_params(params_view(front.spec, args.graph), parse_params(args.param))
    check_probe_buffers(front.source, front.spec)
    culling = cull(front.spec)
    check_geometry(front.spec, list(culling.passes))
    found = warnings(front, culling)
    if args.json:
        emit(document(
            "validate", True, [diagnostic("warning", loc, msg) for loc, msg in found],
            file=str(front.source.path), graph=front.spec.name,
            scene=front.scene.name if front.scene else None, size=list(front.spec.size),
            passes=[p.name for p in culling.passes],
            culled=[{"pass": c.pass_name, "reason": c.reason} for c in culling.culled],
            resources=len(front.spec.resources)))
        return 0
    for loc, msg in found:
        print(escape(f"{loc}: warning: {msg}"), file=sys.stderr)
    scene = f" with scene {quote(front.scene.name)}" if front.scene else ""
    print(
        f"{escape(str(front.source.path))}: ok: graph {quote(front.spec.name)}{scene}: {len(culling.passes)} passes run, "
        f"{len(culling.culled)} culled, {len(front.spec.resources)} resources"
    )
    return 0
