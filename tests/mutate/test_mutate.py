"""Mutation testing (rgraph mutate): every barrier mutant of the bundled surgery graph is caught
by some oracle or explained (documented blind spot / redundant barrier), and the pure mutation
logic (ownership pairs, scope narrowing, explanations) does what the module says."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from rgraph.compiler.pipeline import compile_graph
from rgraph.mutate import (
    BLIND_SPOTS,
    REDUNDANT,
    BarrierUnit,
    Mutant,
    Outcome,
    barrier_units,
    explain,
    mutants,
    mutation_report,
    narrowed_dst,
    supported_accesses,
)
from rgraph.vk.errors import VulkanUnavailable

KNOWN_BLIND_SPOTS = set(BLIND_SPOTS.values())


def surgery(policy: str = "dedicated") -> dict:
    return compile_graph("surgery", size=(32, 32), policy=policy)


def _report(plan: dict, **kw):
    try:
        return mutation_report(plan, **kw)
    except VulkanUnavailable as exc:  # pragma: no cover - environment without Vulkan
        pytest.skip(str(exc))


def _assert_all_explained(report) -> None:
    assert report.baseline.caught_by == [], f"baseline not clean: {report.baseline.as_json()}"
    assert report.baseline.check_error is None, report.baseline.check_error
    unexplained = [o.as_json() for o in report.unexplained()]
    assert not unexplained, json.dumps(unexplained, indent=1)
    for o in report.outcomes:
        if o.mutant.kind == "drop" and not o.caught:
            # a dropped barrier nobody catches must be a documented blind spot or a redundant barrier
            assert o.explanation == REDUNDANT or o.explanation.removeprefix("blind spot: ") in KNOWN_BLIND_SPOTS
        if o.runtime_blind_spot is not None:
            assert o.runtime_blind_spot in KNOWN_BLIND_SPOTS


# ----------------------------------------------------------------------------- pure logic


def test_ownership_pairs_are_one_barrier_with_three_drop_mutants():
    plan = surgery()
    units = barrier_units(plan)
    total = sum(len(p["barriers"]) + len(p["releases"]) for p in plan["passes"])
    pairs = [u for u in units if u.is_pair]
    assert pairs, "surgery has async compute: it must have ownership pairs"
    assert len(units) == total - len(pairs)
    for u in pairs:
        assert u.release.pass_index < u.acquire.pass_index
        assert plan["passes"][u.release.pass_index]["releases"][u.release.position] == u.barrier
    drops = [m for m in mutants(plan, ["drop"]) if m.unit.is_pair]
    assert len(drops) == 3 * len(pairs)
    both = next(m for m in drops if m.name.endswith("(pair)"))
    before = sum(len(p["barriers"]) + len(p["releases"]) for p in plan["passes"])
    after = sum(len(p["barriers"]) + len(p["releases"]) for p in both.plan["passes"])
    assert before - after == 2
    assert sum(len(p["barriers"]) + len(p["releases"]) for p in plan["passes"]) == before  # original untouched


def test_src_access_mutant_only_for_writes_and_changes_both_halves():
    plan = surgery()
    for m in mutants(plan, ["src-access"]):
        assert m.unit.barrier["src"]["access"]
        for site in (m.unit.acquire, m.unit.release):
            if site is not None:
                assert m.plan["passes"][site.pass_index][site.section][site.position]["src"]["access"] == []
    no_write = [u for u in barrier_units(plan) if not u.barrier["src"]["access"]]
    assert len(mutants(plan, ["src-access"])) == len(barrier_units(plan)) - len(no_write)


def test_narrowing_dst_stages():
    dst = {"stages": ["EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"],
           "access": ["DEPTH_STENCIL_ATTACHMENT_READ"], "layout": "DEPTH_READ_ONLY_OPTIMAL", "queue": "graphics"}
    new, note = narrowed_dst(dst)
    assert new["stages"] == ["LATE_FRAGMENT_TESTS"] and new["access"] == ["DEPTH_STENCIL_ATTACHMENT_READ"]
    assert "EARLY_FRAGMENT_TESTS" in note
    new, note = narrowed_dst({**dst, "stages": ["COMPUTE_SHADER"], "access": ["SHADER_SAMPLED_READ"]})
    assert new["stages"] == ["DRAW_INDIRECT"] and new["access"] == []  # stays valid Vulkan
    assert narrowed_dst({**dst, "stages": ["DRAW_INDIRECT"], "access": ["INDIRECT_COMMAND_READ"]}) is None
    assert supported_accesses(["SHADER_SAMPLED_READ", "COLOR_ATTACHMENT_READ"], ["FRAGMENT_SHADER"]) == \
        ["SHADER_SAMPLED_READ"]
    assert supported_accesses(["MEMORY_READ", "TRANSFER_READ"], ["COMPUTE_SHADER"]) == ["MEMORY_READ"]


def _fake(kind: str, barrier: dict) -> Outcome:
    return Outcome(Mutant(f"{kind} x", kind, BarrierUnit(barrier, None, None), "", {}))


BUFFER_BARRIER = {"resource": "b", "subresource": None, "aliases": None,
                  "src": {"stages": ["COMPUTE_SHADER"], "access": ["SHADER_STORAGE_WRITE"], "layout": None,
                          "queue": "graphics"},
                  "dst": {"stages": ["COMPUTE_SHADER"], "access": ["SHADER_STORAGE_READ"], "layout": None,
                          "queue": "graphics"}}


def test_uncaught_without_reason_is_unexplained_unless_every_oracle_ran():
    all_oracles = ["check", "syncval", "data"]
    outcome = _fake("drop", BUFFER_BARRIER)
    explain({"passes": []}, outcome, all_oracles, same_family=True)
    assert outcome.explanation == REDUNDANT  # every oracle clean: the generator emitted a needless barrier
    outcome = _fake("drop", BUFFER_BARRIER)
    explain({"passes": []}, outcome, ["check"], same_family=True)
    assert outcome.explanation.startswith("not caught")
    caught = _fake("drop", BUFFER_BARRIER)
    caught.caught_by = ["check"]
    explain({"passes": []}, caught, all_oracles, same_family=True)
    assert caught.explanation is None


def test_cli_check_only_writes_json_and_rejects_bad_oracles(tmp_path):
    out = tmp_path / "m.json"
    run = subprocess.run([sys.executable, "-m", "rgraph", "mutate", "surgery", "--size", "16x16", "--policy",
                          "dedicated", "--oracles", "check", "--json", str(out), "-q"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    data = json.loads(out.read_text())
    assert data["oracles"] == ["check"]
    assert data["summary"]["drop"]["total"] == len([m for m in data["mutants"] if m["kind"] == "drop"]) > 0
    assert "drop:" in run.stdout
    bad = subprocess.run([sys.executable, "-m", "rgraph", "mutate", "surgery", "--oracles", "check,magic"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "error: --oracles" in bad.stderr and "Traceback" not in bad.stderr


# ----------------------------------------------------------------------------- on the device


@pytest.mark.vulkan
def test_surgery_every_mutant_caught_or_explained():
    """All three mutation kinds on surgery at 32x32 (~20 s on lavapipe): no unexplained survivor."""
    report = _report(surgery())
    _assert_all_explained(report)
    caught, total = report.summary()["drop"]
    assert total > 30 and caught >= total - 3  # surgery: only the same-family ownership pair's drops survive
    # the oracles complement each other: check sees ownership, syncval sees what the plan hides from check
    assert any("syncval" in o.caught_by for o in report.outcomes)
    assert any(o.caught_by == ["check"] for o in report.outcomes)


@pytest.mark.vulkan
def test_surgery_aliased_every_drop_caught_or_explained():
    _assert_all_explained(_report(surgery("aliased"), kinds=["drop"]))


@pytest.mark.vulkan
def test_a_plan_the_probe_cannot_run_stops_before_any_mutant(tmp_path):
    """rt_hybrid's 16-byte ray-list arguments leave no room for the probe's header: the
    unmutated plan fails, so mutate says why and exits 1 (it ran 120 mutants, each 'caught' by
    the same runtime error, and exited 0 until session 21)."""
    from locations import ROOT

    out = tmp_path / "m.json"
    run = subprocess.run([sys.executable, "-m", "rgraph", "mutate", "rt_hybrid", "--scene",
                          str(ROOT / "graphs" / "scenes" / "rt_tiny.yaml"), "--size", "16x16", "--oracles", "syncval",
                          "--json", str(out), "-q"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 1, run.stderr
    assert "the unmutated plan fails, so no mutant was run" in run.stderr and "too small for the probe" in run.stderr
    assert "Traceback" not in run.stderr and not out.exists()
