"""The compiler's phases: a visible list of pure functions over one Compilation."""

from __future__ import annotations

import copy

import networkx as nx
import pytest

from rgraph.compiler.phases import PHASES, Compilation, run_phases
from rgraph.compiler.pipeline import frontend
from rgraph.memory_requirements import ProfileMemoryRequirements
from rgraph.random_graph import random_graph, to_yaml


def _start(tmp_path, seed: int, passes: int) -> Compilation:
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    spec = frontend(path, size=(16, 16)).spec
    return Compilation(spec, "aliased", ProfileMemoryRequirements.named("lavapipe"), "lavapipe")


def test_the_phases_in_order():
    assert [name for name, _ in PHASES] == ["cull", "schedule", "size_accels", "trace", "measure", "place",
                                             "synchronize", "emit"]


@pytest.mark.parametrize("seed", range(4))
def test_phases_are_pure(tmp_path, seed):
    """Each phase returns a new Compilation and leaves its input, and the spec, as they were."""
    c = _start(tmp_path, seed, 30)
    spec_before = copy.deepcopy(c.spec)
    for name, phase in PHASES:
        before = copy.copy(c)
        after = phase(c)
        assert after is not c, name
        assert c == before, f"{name} changed its input"
        c = after
    assert c.spec == spec_before
    assert c.plan is not None and run_phases(_start(tmp_path, seed, 30)).plan == c.plan


@pytest.mark.parametrize("seed", range(6))
def test_schedule_is_the_lexicographic_topological_order(tmp_path, seed):
    """Declaration order of the kept passes is networkx's lexicographic topological order of
    the dependency DAG keyed by declaration index (why the schedule phase needs no sort)."""
    c = run_phases(_start(tmp_path, seed, 40))
    graph = c.graph
    assert nx.is_directed_acyclic_graph(graph)
    order = nx.get_node_attributes(graph, "order")
    topo = list(nx.lexicographical_topological_sort(graph, key=order.__getitem__))
    assert topo == [p.name for p in c.passes] == [p.name for p in c.plan.passes]


def test_size_accels_makes_a_new_spec_and_leaves_the_input_one(tmp_path):
    """Accels are sized into a new Spec (with the build scratch); the specialized one is kept."""
    from locations import TESTS

    spec = frontend(TESTS / "data" / "rt" / "rt_probe.yaml", size=(32, 32)).spec
    before = copy.deepcopy(spec)
    c = run_phases(Compilation(spec, "aliased", ProfileMemoryRequirements.named("lavapipe"), "lavapipe"))
    assert spec == before
    sized = [r for r in c.spec.resources.values() if r.kind == "accel" and r.accel is not None]
    assert sized and all(r.accel is None for r in spec.resources.values() if r.kind == "accel")
    scratch = [r for r in c.spec.resources.values() if r.scratch_of is not None]
    assert {r.scratch_of for r in scratch} <= {r.name for r in sized} and scratch
    assert {r.name for r in scratch} <= {r.name for r in c.plan.resources}
    assert all(r.accel is not None for r in c.plan.resources if r.kind == "accel")
