"""Batch cuts (rgraph.vk.lower.batches.make_batches, no device): on one VkQueue the clustered
frame needs no semaphore, so the default cuts (``queue``) give one batch where the plan's
(``plan``: every wait and signal) give two; on separate graphics / compute / transfer families
every cut stays (each needs a semaphore), so both give the same batches."""

from __future__ import annotations

import pytest
from locations import ROOT

from rgraph.compiler.pipeline import compile_graph
from rgraph.vk.lower.batches import make_batches


class Layout:
    def __init__(self, families: dict[str, int]) -> None:
        self.families = families

    def same_queue(self, a: str, b: str) -> bool:
        return self.families[a] == self.families[b]


ONE = Layout({"graphics": 0, "compute": 0, "transfer": 0})
SEPARATE = Layout({"graphics": 0, "compute": 1, "transfer": 2})


def _names(plan: dict, layout: Layout, cuts: str) -> list[list[str]]:
    return [[p["name"] for p in b.passes] for b in make_batches(plan, layout, cuts=cuts)]


@pytest.mark.parametrize("scene", ["vr_skinned.yaml", "lighting_test.yaml"])
def test_cuts_only_where_a_semaphore_is_needed(scene):
    plan = compile_graph(ROOT / "graphs" / "clustered.yaml", scene_path=ROOT / "graphs" / "scenes" / scene,
                         size=(32, 18), params={"draw.mode": "gpu"})
    assert any(p["waits"] for p in plan["passes"])  # the plan orders its queues
    assert _names(plan, ONE, "queue") == [[p["name"] for p in plan["passes"]]]
    assert len(_names(plan, ONE, "plan")) == 2
    separate = _names(plan, SEPARATE, "queue")
    assert separate == _names(plan, SEPARATE, "plan") and len(separate) > 2
    with pytest.raises(ValueError, match="batch cuts must be one of"):
        make_batches(plan, ONE, cuts="never")
