"""``--balance dynamic`` on two logical devices of lavapipe (validation on): layouts are loaded
once each and reused, frame numbers continue across them (the probe's data check of the last
frame passes), and equal devices keep nearly equal bands."""

from __future__ import annotations

from dataclasses import replace

from locations import ROOT
from multi_helpers import assert_data_ok

from rgraph.api import open_device
from rgraph.compiler.multi_device import Split
from rgraph.compiler.pipeline import compile_graph, compile_graph_plan
from rgraph.vk.multi.balance import DynamicBalance

PROBE_GRAPH = ROOT / "tests" / "multi_graphs" / "probe_split.yaml"
SIZE = (64, 64)
FRAMES = 6


def test_dynamic_balance_reuses_layouts_and_keeps_frame_numbers():
    gpus = [open_device(validate=True, device=0, verbose=False) for _ in range(2)]
    try:
        memory = gpus[0].memory_requirements()
        reference = compile_graph(PROBE_GRAPH, size=SIZE, memory=memory)
        split = Split(2, "sort-first", "dynamic")
        balance = DynamicBalance(gpus, lambda w: compile_graph_plan(PROBE_GRAPH, size=SIZE, memory=memory,
                                                                    split=replace(split, weights=w)))
        try:
            summary = balance.run(FRAMES)
            assert balance.loads == len(set(balance.layouts)) <= FRAMES  # one load per distinct layout
            assert all(sum(rows) == SIZE[1] and min(rows) >= 8 for rows in balance.layouts)
            assert [r for _y, r in balance.plan.multi_device["bands"]] == list(balance.layouts[-1])
            assert summary.findings == []
            assert balance.current.frames_done == FRAMES
            data = balance.read_back()
        finally:
            balance.close()
        assert_data_ok(reference, data, FRAMES)
    finally:
        messages = [m for g in gpus for m in g.close()]
    assert messages == []
