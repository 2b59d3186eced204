"""Property tests on random valid graphs: every plan is hazard-free by `check`, and every
barrier is necessary: deleting any single one makes `check` report a hazard."""

from __future__ import annotations

import copy
import os
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rgraph.check import check_plan
from rgraph.compile.pipeline import compile_spec, frontend
from rgraph.random_graph import random_graph, to_yaml

EXAMPLES = int(os.environ.get("RGRAPH_FUZZ_EXAMPLES", "40"))
POLICIES = ("dedicated", "aliased")


def plan_for(tmp: Path, seed: int, passes: int, policy: str) -> dict:
    path = tmp / f"g_{seed}_{passes}.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    return compile_spec(frontend(path, size=(16, 16)).spec, policy=policy)


def describe(hazards) -> str:
    return "\n".join(str(h) for h in hazards[:10])


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(1, 60), policy=st.sampled_from(POLICIES))
def test_random_plans_are_clean(tmp_path: Path, seed: int, passes: int, policy: str) -> None:
    plan = plan_for(tmp_path, seed, passes, policy)
    hazards = check_plan(plan)
    assert not hazards, describe(hazards)


@settings(max_examples=max(5, EXAMPLES // 4), deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(2, 40), policy=st.sampled_from(POLICIES))
def test_every_barrier_is_necessary(tmp_path: Path, seed: int, passes: int, policy: str) -> None:
    plan = plan_for(tmp_path, seed, passes, policy)
    for i, p in enumerate(plan["passes"]):
        for section in ("barriers", "releases"):
            for j in range(len(p[section])):
                mutated = copy.deepcopy(plan)
                removed = mutated["passes"][i][section].pop(j)
                hazards = check_plan(mutated)
                assert hazards, f"removing {section[:-1]} {removed} before/after pass {p['name']} went unnoticed"
