"""graphs/async_overlap.yaml on lavapipe under validation, and the plans of
benchmarks/barrier_cost.py (graph, naive, one queue, no barriers)."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT

from rgraph.compiler.pipeline import compile_graph

GRAPH = ROOT / "graphs" / "async_overlap.yaml"
SIZE = (64, 48)
PARAMS = {"shadow.size": "256", "particles.count": "4096", "particles.substeps": "2"}
COMPUTE_QUEUE = {"ao_downsample", "ao_trace", "ao_upsample", "particles_sim"}


def test_the_queues_overlap_until_forward() -> None:
    plan = compile_graph(GRAPH, params=PARAMS, size=SIZE)
    by_name = {p["name"]: p for p in plan["passes"]}
    assert {n for n, p in by_name.items() if p["queue"] == "compute"} == COMPUTE_QUEUE
    graphics_waits = {n: p["waits"] for n, p in by_name.items() if p["queue"] == "graphics" and p["waits"]}
    assert set(graphics_waits) == {"forward", "particles_draw"}  # shadow and IBL run beside the compute work
    signals = [n for n, p in by_name.items() if p["queue"] == "compute" and p["signals"]]
    assert signals == ["ao_upsample", "particles_sim"]  # forward waits for the AO, not the particles
    assert all(p["impl"] for p in plan["passes"])


@pytest.mark.vulkan
def test_async_overlap_renders_clean_with_real_passes() -> None:
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPH, params=PARAMS, size=SIZE)
    result = execute_plan(plan, validate=True, frames=3, read_outputs=True)
    assert [m.text for m in result.messages] == []
    color = result.outputs["color"]
    assert color.shape == (SIZE[1], SIZE[0], 4) and np.isfinite(color).all()
    assert color[..., :3].std() > 0.02, "a real picture, not a flat fill"


@pytest.mark.vulkan
def test_barrier_cost_plans_and_validation_of_the_safe_ones() -> None:
    from benchmarks.barrier_cost import plans, validate
    from rgraph.vk.memreq import live_requirements

    with live_requirements() as (memory, _device):
        built = plans(str(GRAPH), SIZE, PARAMS, memory)
    assert built["graph"]["queues"] == ["graphics", "compute"]
    assert all(built[m]["queues"] == ["graphics"] for m in ("naive", "one_queue", "none"))
    assert built["none"]["stats"]["barriers"] == 0 and built["one_queue"]["stats"]["barriers"] > 0
    assert not any(p["barriers"] or p["waits"] for p in built["none"]["passes"])
    names = [[p["name"] for p in built[m]["passes"]] for m in built]
    assert all(n == names[0] for n in names)
    for mode in ("graph", "naive", "one_queue"):
        validate(built[mode], mode)  # raises SystemExit on any message
