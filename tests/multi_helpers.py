"""Shared by the multi-device tests (tests/vk/test_multi_*.py): two validated logical devices
of one physical device, and the probe's data check of a composited frame."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from rgraph.api import open_device
from rgraph.compiler.multi_device import Split
from rgraph.compiler.pipeline import compile_graph, compile_graph_plan
from rgraph.probe.check import check_outputs
from rgraph.vk.multi.run import MultiExecutable
from rgraph.vk.runtime.readback import decode_outputs


def validated_pair(count: int = 2) -> Iterator[list[Any]]:
    """Body of a module fixture: ``count`` logical devices on device 0, validation on; every
    one must close without a message."""
    devices = [open_device(validate=True, device=0, verbose=False) for _ in range(count)]
    yield devices
    for g in devices:
        assert g.close() == [], "validation messages"


def assert_data_ok(reference: dict, data: dict, frames: int) -> None:
    """The probe's data check of device 0's own resources (not the received buffers) against
    the one-device plan ``reference`` after ``frames`` frames."""
    known = {r["name"] for r in reference["resources"]}
    verdict = check_outputs(reference, {k: v for k, v in data.items() if k[0] in known}, frames)
    assert verdict.ok is True, [str(m) for m in verdict.mismatches]


def outputs_one_and_split(gpus: list[Any], graph: str, mode: str, size: tuple[int, int], scene: Any = None,
                          params: dict[str, str] | None = None) -> tuple[Any, dict, dict]:
    """``graph`` run for one frame on ``gpus[0]`` alone and split ``mode`` over all of them: the
    one-device plan and both runs' decoded outputs."""
    plan = compile_graph(graph, scene, params=params, size=size, memory=gpus[0].memory_requirements())
    with gpus[0].load(plan) as exe:
        exe.run(1)
        one = decode_outputs(plan, exe.read_back())
    split = compile_graph_plan(graph, scene, params=params, size=size, memory=gpus[0].memory_requirements(),
                               split=Split(len(gpus), mode))
    multi = MultiExecutable(gpus, split)
    try:
        multi.run(1)
        out = decode_outputs(multi.plans[0], multi.read_back())
    finally:
        multi.close()
    return plan, one, out
