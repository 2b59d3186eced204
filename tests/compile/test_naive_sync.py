"""``--sync naive``: a full barrier before every pass, one queue, no semaphores; the plan
passes ``rgraph check`` and runs clean under validation with exact probe data."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rgraph.check import check_plan
from rgraph.cli import main
from rgraph.compiler.naive_sync import naive_sync
from rgraph.compiler.pipeline import compile_graph, compile_spec, frontend
from rgraph.random_graph import random_graph, to_yaml


def _cells(sub, res):
    if sub is None:
        return {(0, 0)}
    return {(m, la) for m in range(*sub["mips"]) for la in range(*sub["layers"])}


def assert_naive(plan: dict, normal: dict) -> None:
    resources = {r["name"]: r for r in plan["resources"]}
    assert plan["stats"]["sync"] == "naive" and plan["stats"]["semaphores"] == 0
    assert plan["queues"] == ["graphics"]
    assert [p["name"] for p in plan["passes"]] == [p["name"] for p in normal["passes"]]
    assert [(r["name"], r["heap"], r["offset"]) for r in plan["resources"]] == [
        (r["name"], r["heap"], r["offset"]) for r in normal["resources"]]
    assert plan["stats"]["barriers"] == sum(len(p["barriers"]) for p in plan["passes"])
    for p in plan["passes"]:
        assert p["queue"] == "graphics" and p["waits"] == p["signals"] == p["releases"] == []
        for b in p["barriers"]:
            assert b["src"]["stages"] == ["ALL_COMMANDS"] and b["src"]["access"] == ["MEMORY_WRITE"]
            assert b["dst"]["stages"] == ["ALL_COMMANDS"] and b["dst"]["access"] == ["MEMORY_READ", "MEMORY_WRITE"]
            assert b["src"]["queue"] == b["dst"]["queue"] == "graphics"
        for a in p["accesses"]:
            covered = set()
            for b in p["barriers"]:
                if b["resource"] == a["resource"]:
                    assert b["dst"]["layout"] == a["layout"] or not _cells(b["subresource"], None) & _cells(
                        a["subresource"], None)
                    covered |= _cells(b["subresource"], resources[a["resource"]])
            assert _cells(a["subresource"], resources[a["resource"]]) <= covered, (p["name"], a["resource"])
    assert check_plan(plan) == []


def test_surgery_naive_plan():
    normal = compile_graph("surgery", size=(320, 180))
    naive = compile_graph("surgery", size=(320, 180), sync="naive")
    assert naive == naive_sync(normal)
    assert_naive(naive, normal)
    assert naive["stats"]["barriers"] > normal["stats"]["barriers"]
    assert normal["stats"].get("sync") is None  # normal plans are unchanged (goldens)


@pytest.mark.parametrize("seed", range(25))
def test_naive_plans_of_random_graphs_check_clean(tmp_path: Path, seed: int):
    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed, 12)))
    for policy in ("aliased", "dedicated"):
        normal = compile_spec(frontend(path, size=(16, 16)).spec, policy=policy)
        assert_naive(naive_sync(normal), normal)


def test_compile_command_writes_a_naive_plan(tmp_path: Path):
    out = tmp_path / "plan.json"
    assert main(["compile", "surgery", "--size", "64x64", "--sync", "naive", "-o", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["stats"]["sync"] == "naive"
    assert main(["check", str(out)]) == 0


def test_unknown_sync_mode_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["compile", "surgery", "--sync", "fast"])
    assert exc.value.code == 2
    assert "--sync" in capsys.readouterr().err


@pytest.mark.vulkan
@pytest.mark.parametrize(("seed", "passes", "policy"), [
    (0, 8, "dedicated"), (9, 8, "aliased"), (32, 10, "aliased"), (4, 16, "dedicated"), (1, 12, "aliased"),
    (2, 12, "dedicated"), (3, 12, "aliased"),
])
def test_naive_random_graphs_run_clean_with_exact_data(tmp_path: Path, memory, seed: int, passes: int, policy: str):
    from rgraph.vk.executor import execute_plan

    path = tmp_path / "g.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    plan = naive_sync(compile_spec(frontend(path, size=(16, 16)).spec, policy=policy, memory_provider=memory))
    result = execute_plan(plan, validate=True, frames=2, check_data=True)
    assert [str(m) for m in result.messages] == []
    assert result.data_ok is True, [str(m) for m in result.mismatches[:5]]


@pytest.mark.vulkan
def test_naive_surgery_with_probe_passes_runs_clean_with_exact_data(memory):
    from rgraph.vk.executor import execute_plan

    plan = compile_graph("surgery", size=(64, 64), memory=memory, sync="naive")
    plan = {**plan, "passes": [{**p, "impl": None} for p in plan["passes"]]}
    result = execute_plan(plan, validate=True, frames=2, check_data=True)
    assert [str(m) for m in result.messages] == []
    assert result.data_ok is True, [str(m) for m in result.mismatches[:5]]
