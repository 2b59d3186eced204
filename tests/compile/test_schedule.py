"""``--schedule``: declaration order by default; ``async-early`` moves async passes up as far
as dependencies allow, and the frame it computes is the same (checked on lavapipe)."""

from __future__ import annotations

from pathlib import Path

import pytest
from locations import TESTS

from rgraph.check import check_plan
from rgraph.compiler.pipeline import compile_graph
from rgraph.errors import RGraphError

GRAPH = (TESTS / "pass_graphs" / "async_compute.yaml").read_text()


@pytest.fixture
def graph(tmp_path: Path) -> Path:
    path = tmp_path / "sched.yaml"
    path.write_text(GRAPH)
    return path


def names(plan: dict) -> list[str]:
    return [p["name"] for p in plan["passes"]]


def test_declaration_is_the_default_and_async_early_moves_compute_up(graph):
    default = compile_graph(graph, size=(32, 32))
    assert names(default) == ["prepass", "gbuffer", "ao", "light"]
    assert "schedule" not in default["stats"]
    early = compile_graph(graph, size=(32, 32), schedule="async-early")
    assert names(early) == ["prepass", "ao", "gbuffer", "light"]
    assert early["stats"]["schedule"] == "async-early"
    assert check_plan(early) == []


def test_unknown_schedule_is_refused(graph):
    with pytest.raises(RGraphError, match="--schedule expects one of declaration, async-early"):
        compile_graph(graph, size=(32, 32), schedule="fastest")


def test_async_early_runs_clean_and_computes_the_same_frame(graph):
    from rgraph.api import compile_for_device
    from rgraph.vk.executor import execute_plan

    outputs = {}
    for mode in ("declaration", "async-early"):
        plan = compile_for_device(graph, None, size=(32, 32), schedule=mode)
        result = execute_plan(plan, validate=True, frames=2, check_data=True, read_outputs=True)
        assert [str(m) for m in result.messages] == [], mode
        assert result.data_ok, (mode, result.mismatches)
        outputs[mode] = result.outputs["color"]
    assert (outputs["declaration"] == outputs["async-early"]).all()
