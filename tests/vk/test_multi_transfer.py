"""The two cross-device transfers (shared host allocation via VK_EXT_external_memory_host, and
the staged readback + refill) and pipelined frames, on two logical devices of lavapipe under
validation + synchronization validation: the composited frame equals the one-device frame."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT
from multi_helpers import assert_data_ok, validated_pair

from rgraph.compiler.multi_device import Split
from rgraph.compiler.pipeline import compile_graph, compile_graph_plan
from rgraph.vk.errors import ExecutionError
from rgraph.vk.multi.run import MultiExecutable, host_import_supported
from rgraph.vk.runtime.readback import decode_outputs

PROBE_GRAPH = ROOT / "tests" / "multi_graphs" / "probe_split.yaml"
SIZE = (64, 48)
FRAMES = 3


@pytest.fixture(scope="module")
def gpus():
    yield from validated_pair()


def _messages(gpus):
    return [m for g in gpus for m in g.instance.log.messages]


def test_lavapipe_offers_the_shared_host_allocation(gpus):
    """The shared path is what these tests exercise on lavapipe (it offers the extension)."""
    assert all(host_import_supported(g) for g in gpus)


@pytest.mark.parametrize("pipelined", [False, True], ids=["serial", "pipelined"])
@pytest.mark.parametrize("transfer", ["shared", "staged"])
@pytest.mark.parametrize("mode", ["sort-first", "sort-last"])
def test_transfer_and_pipelining_keep_the_one_device_frame(gpus, mode, transfer, pipelined):
    memory = gpus[0].memory_requirements()
    reference = compile_graph(PROBE_GRAPH, size=SIZE, memory=memory)
    with gpus[0].load(reference) as exe:
        exe.run(FRAMES)
        ref = decode_outputs(reference, exe.read_back())
    plan = compile_graph_plan(PROBE_GRAPH, size=SIZE, memory=memory, split=Split(2, mode))
    multi = MultiExecutable(gpus, plan, transfer=transfer, pipelined=pipelined)
    try:
        summary = multi.run(FRAMES)
        if transfer == "shared":  # the tiles went through the shared bytes, not the host copy
            assert summary.readback_ms == 0.0
            assert len(multi.bridges) == 2 * len(plan.multi_device["crossing"])
            if mode == "sort-first":  # (the probe's one draw is device 0's share under sort-last: tests/vk/test_multi_workloads.py)
                assert all(any(b.read()) for b in multi.bridges)  # every frame set's allocation got a tile
        data = multi.read_back()
    finally:
        multi.close()
    assert summary.transfer == transfer and summary.pipelined == pipelined
    assert summary.findings == []  # every device's span covers all its passes, inside its host wait
    assert len(summary.samples) == FRAMES
    assert_data_ok(reference, data, FRAMES)
    assert np.array_equal(ref["color"], decode_outputs(multi.plans[0], data)["color"])
    assert _messages(gpus) == []


def test_pipelined_runs_continue_frame_counts(gpus):
    """Two pipelined run() calls in a row: frame-in-flight sets stay aligned across devices."""
    memory = gpus[0].memory_requirements()
    reference = compile_graph(PROBE_GRAPH, size=SIZE, memory=memory)
    plan = compile_graph_plan(PROBE_GRAPH, size=SIZE, memory=memory, split=Split(2, "sort-first"))
    multi = MultiExecutable(gpus, plan, transfer="shared", pipelined=True)
    try:
        multi.run(2)
        multi.run(3)
        assert multi.frames_done == 5 and all(s.executor.frames_done == 5 for s in multi.senders)
        data = multi.read_back()
    finally:
        multi.close()
    assert_data_ok(reference, data, 5)
    assert _messages(gpus) == []


def test_unknown_transfer_is_refused(gpus):
    plan = compile_graph_plan(PROBE_GRAPH, size=SIZE, memory=gpus[0].memory_requirements(),
                              split=Split(2, "sort-first"))
    with pytest.raises(ExecutionError, match="transfer"):
        MultiExecutable(gpus, plan, transfer="teleport")


def test_auto_falls_back_to_staged_when_the_import_is_refused(gpus, monkeypatch):
    """A driver refusing the host-pointer import: ``auto`` runs staged (and says why), an
    explicit ``shared`` is an ExecutionError."""
    from rgraph.vk.multi import host_memory

    def refuse(*_a, **_k):
        raise RuntimeError("import refused")

    monkeypatch.setattr(host_memory.SharedHostBuffer, "create", classmethod(lambda cls, *a, **k: refuse()))
    plan = compile_graph_plan(PROBE_GRAPH, size=SIZE, memory=gpus[0].memory_requirements(),
                              split=Split(2, "sort-first"))
    multi = MultiExecutable(gpus, plan)
    try:
        assert multi.transfer == "staged" and "import refused" in multi.shared_error
        assert multi.run(1).transfer == "staged"
    finally:
        multi.close()
    with pytest.raises(ExecutionError, match="shared host allocation was refused"):
        MultiExecutable(gpus, plan, transfer="shared")
    assert _messages(gpus) == []
