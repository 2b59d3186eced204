"""Semaphore waits order only the stages in their stage mask (VkSemaphoreSubmitInfo::stageMask
limits a wait's second synchronization scope), and a barrier chains after a wait only through
source stages that meet it (the swapchain-acquire pattern)."""

from __future__ import annotations

import copy

from rgraph.check import ALIASING_HANDOFF, RAW, check_plan
from rgraph.compiler.pipeline import compile_graph


def _surgery() -> dict:
    return compile_graph("surgery", size=(32, 32))


def _pass(plan: dict, name: str) -> dict:
    return next(p for p in plan["passes"] if p["name"] == name)


def test_surgery_plan_is_clean():
    assert check_plan(_surgery()) == []


def test_dropped_lights_barrier_is_a_raw_at_the_vertex_stage():
    """light_setup writes 'lights' in a compute shader on the graphics queue; forward reads it as a
    uniform in VERTEX and FRAGMENT. The semaphore chain through the compute queue reaches forward's
    wait stages (fragment and later), never its vertex shader: the barrier is needed."""
    plan = _surgery()
    forward = _pass(plan, "forward")
    assert "VERTEX_SHADER" not in {s for w in forward["waits"] for s in w["stages"]}
    forward["barriers"] = [b for b in forward["barriers"] if b["resource"] != "lights"]
    hazards = check_plan(plan)
    assert [h.kind for h in hazards] == [RAW]
    assert hazards[0].resource == "lights" and "missing for VERTEX_SHADER" in hazards[0].message


def test_a_wait_that_misses_the_barriers_source_stages_orders_nothing_for_it():
    """forward's first barrier on 'normal_sss' hands memory over from resources the compute queue
    used; its source stage (COMPUTE_SHADER) must be in the wait's stages for the chain to form."""
    plan = _surgery()
    forward = _pass(plan, "forward")
    (wait,) = [w for w in forward["waits"] if w["queue"] == "compute"]
    assert "COMPUTE_SHADER" in wait["stages"]
    narrowed = copy.deepcopy(plan)
    (wait,) = [w for w in _pass(narrowed, "forward")["waits"] if w["queue"] == "compute"]
    wait["stages"] = [s for s in wait["stages"] if s != "COMPUTE_SHADER"]
    kinds = {h.kind for h in check_plan(narrowed)}
    assert ALIASING_HANDOFF in kinds


def test_an_all_commands_wait_covers_every_stage():
    """With an ALL_COMMANDS wait the chain through the compute queue reaches the vertex shader too,
    so the 'lights' barrier becomes redundant: the model is precise, not merely stricter."""
    plan = _surgery()
    forward = _pass(plan, "forward")
    for w in forward["waits"]:
        w["stages"] = ["ALL_COMMANDS"]
    forward["barriers"] = [b for b in forward["barriers"] if b["resource"] != "lights"]
    assert check_plan(plan) == []
