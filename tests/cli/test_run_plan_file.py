"""``rgraph run PLAN.json`` loads through the typed loader and runs ``rgraph check`` first:
malformed plans and plans with hazards are refused with one line and exit 2 (issue 14);
``--unchecked`` runs them anyway; ``--size`` and other compile flags are refused for plans."""

from __future__ import annotations

import copy
import json
import re

import pytest

from rgraph.cli import main
from rgraph.compiler.pipeline import compile_graph

ONE_LINE = re.compile(r"^\S+:\d+:\d+: error: .+$")


@pytest.fixture(scope="module")
def surgery() -> dict:
    return compile_graph("surgery", size=(64, 64), profile="lavapipe")


def _first(plan: dict, key: str) -> dict:
    return next(p for p in plan["passes"] if p[key])


def _drop_barrier(p):
    _first(p, "barriers")["barriers"].pop(0)


def _drop_release(p):
    _first(p, "releases")["releases"].pop(0)


def _drop_wait(p):
    _first(p, "waits")["waits"].pop(0)


def _bogus_layout(p):
    b = next(b for q in p["passes"] for b in q["barriers"] if b["dst"]["layout"] not in (None, "GENERAL"))
    b["dst"]["layout"] = "GENERAL"


def _reversed(p):
    p["passes"].reverse()
    for i, q in enumerate(p["passes"]):
        q["index"] = i


def _missing_barriers(p):  # KeyError in the runtime before the typed loader
    del p["passes"][2]["barriers"]


def _huge_extent(p):  # OverflowError
    p["resources"][0]["extent"] = [10**30, 1, 1]


def _zero_alignment(p):  # ZeroDivisionError
    p["heaps"][0]["alignment"] = 0


def _zero_size(p):
    p["size"] = [0, 0]


HAZARDS = [_drop_barrier, _drop_release, _drop_wait, _bogus_layout, _reversed]
MALFORMED = [_missing_barriers, _huge_extent, _zero_alignment, _zero_size]


def _run(tmp_path, capsys, plan: dict, *extra: str) -> tuple[int, list[str]]:
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    capsys.readouterr()
    rc = main(["run", str(path), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    return rc, err


@pytest.mark.parametrize(("mutate", "expected"), [(m, "rgraph check finds") for m in HAZARDS]
                         + [(m, "malformed plan") for m in MALFORMED], ids=lambda f: getattr(f, "__name__", "")[1:])
def test_bad_plans_are_refused_with_one_line(tmp_path, capsys, surgery, mutate, expected):
    """Plans with hazards name ``rgraph check`` and ``--unchecked``; malformed ones their JSON path."""
    plan = copy.deepcopy(surgery)
    mutate(plan)
    rc, err = _run(tmp_path, capsys, plan)
    assert rc == 2
    assert len(err) == 1 and ONE_LINE.match(err[0]) and expected in err[0], err
    if expected == "rgraph check finds":
        assert "--unchecked" in err[0]


def test_not_json_is_one_line(tmp_path, capsys):
    path = tmp_path / "plan.json"
    path.write_text("{not json")
    rc = main(["run", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and ONE_LINE.match(err[0]), err


@pytest.mark.parametrize("flags", [["--size", "32x32"], ["--size", "640x360"], ["--policy", "dedicated"], ["-p", "x=1"],
                                   ["--schedule", "async-early"]])
def test_compile_flags_are_refused_for_a_plan(tmp_path, capsys, surgery, flags):
    rc, err = _run(tmp_path, capsys, surgery, *flags)
    assert rc == 2
    assert len(err) == 1 and "only applies when compiling a graph" in err[0] and "64x64" in err[0], err


@pytest.mark.vulkan
def test_clean_plan_runs_and_unchecked_runs_a_refused_one(tmp_path, capsys):
    """The checker does not stand in the way of clean plans (compiled for the live device),
    and ``--unchecked`` executes a plan it would refuse."""
    from rgraph.api import compile_for_device

    plan = compile_for_device("surgery", size=(64, 64))
    rc, err = _run(tmp_path, capsys, plan, "--validate")
    assert rc == 0, err
    assert any(line.startswith("rgraph: 0 validation message(s)") for line in err), err
    dropped = copy.deepcopy(plan)
    _drop_release(dropped)
    assert _run(tmp_path, capsys, dropped)[0] == 2
    rc, err = _run(tmp_path, capsys, dropped, "--unchecked")
    assert rc == 0, err
