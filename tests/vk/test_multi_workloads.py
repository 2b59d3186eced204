"""The study's workloads (benchmarks/multi_gpu_work) split over two logical devices of lavapipe,
validation + synchronization validation on: the per-pixel-heavy pass (sort-first) and the
procedural mesh (sort-last: each device draws half of the chunks, composited by depth; and
sort-first) give the one-device image exactly, through both transfers."""

from __future__ import annotations

import numpy as np
import pytest
from multi_helpers import validated_pair

from benchmarks import multi_gpu_work as work
from rgraph.compiler.multi_device import Split
from rgraph.compiler.pipeline import compile_graph, compile_graph_plan
from rgraph.vk.multi.run import MultiExecutable
from rgraph.vk.runtime.readback import decode_outputs

SIZE = (64, 40)
CASES = {"pixels": (work.PIXELS, {"mg.iterations": "32"}),
         "mesh": (work.MESH, {"mg.triangles": "20000", "mg.chunks": "8"})}


@pytest.fixture(scope="module")
def gpus():
    yield from validated_pair()


def _one(gpu, graph, params):
    plan = compile_graph(graph, size=SIZE, memory=gpu.memory_requirements(), params=params)
    with gpu.load(plan) as exe:
        exe.run(2)
        return decode_outputs(plan, exe.read_back())["color"]


@pytest.mark.parametrize("transfer", ["shared", "staged"])
@pytest.mark.parametrize(("name", "mode"), [("pixels", "sort-first"), ("mesh", "sort-last"), ("mesh", "sort-first")])
def test_workload_split_equals_one_device(gpus, name, mode, transfer):
    graph, params = CASES[name]
    ref = _one(gpus[0], graph, params)
    plan = compile_graph_plan(graph, size=SIZE, memory=gpus[0].memory_requirements(), params=params,
                              split=Split(2, mode))
    assert list(plan.multi_device["tiled"]) == (["mesh"] if name == "mesh" else ["shade"])
    multi = MultiExecutable(gpus, plan, transfer=transfer, pipelined=True)
    try:
        summary = multi.run(2)
        out = decode_outputs(multi.plans[0], multi.read_back())["color"]
    finally:
        multi.close()
    assert summary.findings == []
    assert np.array_equal(ref, out)
    assert [m for g in gpus for m in g.instance.log.messages] == []


def test_mesh_halves_are_both_needed(gpus):
    """Control: device 0's chunks alone (its sort-last share) miss part of the one-device image."""
    graph, params = CASES["mesh"]
    ref = _one(gpus[0], graph, params)
    plan = compile_graph_plan(graph, size=SIZE, memory=gpus[0].memory_requirements(), params=params,
                              split=Split(2, "sort-last"))
    from rgraph.plan import to_json_dict
    from rgraph.plan.devices import project

    plan0 = to_json_dict(project(plan, 0))
    zeros = {r["name"]: bytes(r["size_bytes"] or r["bytes"]) for r in plan0["resources"] if ".from1" in r["name"]}
    with gpus[0].load(plan0, inputs=zeros) as exe:
        exe.run(1)
        out = decode_outputs(plan0, exe.read_back())["color"]
    assert not np.array_equal(ref, out)


def test_mesh_chunks_split_contiguously():
    assert [work.chunk_range(8, [d, 2]) for d in range(2)] == [(0, 4), (4, 8)]
    assert [work.chunk_range(7, [d, 3]) for d in range(3)] == [(0, 2), (2, 4), (4, 7)]
    assert work.chunk_range(8, None) == (0, 8)
    assert abs(work.mesh_triangles(100_000_000, 64) - 100_000_000) < 0.001 * 100_000_000
