"""``rgraph run G --devices 0,1 --split sort-first|sort-last``: a multi-device plan on several logical devices.

Compiles the graph twice with the first device's memory requirements: split (what runs)
and unsplit (what the probe's data check predicts: the composited outputs must equal the
one-device frame). A multi-device plan file runs as is (its data check needs the graph).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

from rgraph.commands.common import parse_params, parse_size
from rgraph.vk.instance import validation_summary

if TYPE_CHECKING:
    from rgraph.plan import Plan


def _runtime_options(args: argparse.Namespace) -> dict[str, Any]:
    return {"transfer": getattr(args, "transfer", "auto") or "auto", "pipelined": bool(getattr(args, "pipelined", False))}


def run_multi(args: argparse.Namespace, devices: list[int], default_size: str, plan_file: Plan | None = None) -> int:
    """Run a graph (compiled here, split) or a plan file (``plan_file``: its model, loaded and
    checked by the caller) on ``devices``."""
    from rgraph.api import open_device
    from rgraph.commands.multi_args import split_from_args
    from rgraph.compiler.pipeline import compile_graph, compile_graph_plan
    from rgraph.plan import load
    from rgraph.probe.check import check_outputs
    from rgraph.vk.errors import ExecutionError, VulkanUnavailable
    from rgraph.vk.multi.run import MultiExecutable

    gpus: list[Any] = []
    try:
        for index in devices:
            gpus.append(open_device(validate=args.validate, device=index))
        if args.graph.endswith(".json"):
            plan, reference = plan_file if plan_file is not None else load(args.graph), None
        else:
            options = dict(scene_path=args.scene, params=parse_params(args.param),
                           size=parse_size(args.size or default_size), policy=args.policy,
                           camera=args.camera, sync=args.sync, schedule=args.schedule,
                           memory=gpus[0].memory_requirements())
            split = split_from_args(args, indices=True)
            plan = compile_graph_plan(args.graph, split=split, **options)
            reference = compile_graph(args.graph, **options)
        if args.balance == "dynamic" and reference is not None and plan.multi_device["split"] == "sort-first":
            from dataclasses import replace

            from rgraph.vk.multi.balance import run_balanced

            multi, summary, history = run_balanced(
                gpus, lambda w: compile_graph_plan(args.graph, split=replace(split, weights=w), **options),
                args.frames, **_runtime_options(args))
            plan = multi.plan
            print("rgraph: shares per frame: " + " -> ".join("/".join(f"{x:.2f}" for x in w) for w in history)
                  + f"; {multi.loads} plan load(s) for {args.frames} frame(s)", file=sys.stderr)
        else:
            multi = MultiExecutable(gpus, plan, **_runtime_options(args))
            warm = getattr(args, "warmup", None)
            multi.warm_up(gpus[0].default_warmup_s if warm is None else warm)
            summary = multi.run(args.frames)
        frames = getattr(multi, "frames_done", args.frames)  # warm-up frames included (the data check counts them)
        data = multi.read_back()
        check = args.validate if args.check_data is None else args.check_data
        verdict = None
        if check and reference is not None:  # device 0's own resources (not the received buffers)
            known = {r["name"] for r in reference["resources"]}
            verdict = check_outputs(reference, {k: v for k, v in data.items() if k[0] in known}, frames)
        if args.out:
            from rgraph.png import write_output_png

            write_output_png(multi.plans[0], data, args.out)
        multi.close()
        messages = [m for g in gpus for m in g.close()]
    except (VulkanUnavailable, ExecutionError) as exc:
        for g in gpus:
            g.close()
        print(f"rgraph: error: {exc}", file=sys.stderr)
        return 2
    info = plan.multi_device or {}
    print(f"rgraph: {info.get('split')} over {len(devices)} logical devices {devices}: frame {summary.frame_ms:.2f} ms "
          f"(host), device GPU ms {[round(x, 3) for x in summary.device_ms]}, readback {summary.readback_ms:.2f} ms, "
          f"device 0 frame {summary.device0_ms:.2f} ms; VK_EXT_external_memory_host offered: "
          f"{summary.host_memory_import} ({summary.transfer} transfer)", file=sys.stderr)
    if args.timings:
        args.timings.write_text(json.dumps({"devices": devices, "frame_ms": summary.frame_ms,
                                            "device_ms": summary.device_ms, "readback_ms": summary.readback_ms,
                                            "device0_ms": summary.device0_ms, "transfer": summary.transfer,
                                            **summary.timings}, indent=1,
                                           sort_keys=True) + "\n")
    status = 0
    for message in messages:
        print(str(message), file=sys.stderr)
    if args.validate:
        print(validation_summary(len(messages)), file=sys.stderr)
        status = 1 if messages else 0
    if verdict is not None and verdict.ok is not None:
        for mismatch in verdict.mismatches:
            print(f"rgraph: data mismatch: {mismatch}", file=sys.stderr)
        note = f" ({len(verdict.unchecked)} subresource(s) not predictable)" if verdict.unchecked else ""
        print(f"rgraph: data check {'ok' if verdict.ok else 'FAILED'} against the one-device plan{note}",
              file=sys.stderr)
        status = status or (0 if verdict.ok else 1)
    if args.out:
        print(f"rgraph: wrote {args.out}", file=sys.stderr)
    return status
