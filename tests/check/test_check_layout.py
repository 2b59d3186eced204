"""check verifies the memory layout and refuses malformed plans with one located line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rgraph.check import MEMORY_LAYOUT, check_plan
from rgraph.cli import main
from rgraph.compiler.pipeline import compile_graph


@pytest.fixture(scope="module")
def plan() -> dict:
    return compile_graph("surgery", size=(32, 32))


def _placed(plan: dict) -> dict:
    return next(r for r in plan["resources"] if r.get("heap") is not None and r["bytes"] > 0)


def _heap(plan: dict, hid: int) -> dict:
    return next(h for h in plan["heaps"] if h["id"] == hid)


def _layout(plan: dict) -> list[str]:
    return [h.message for h in check_plan(plan) if h.kind == MEMORY_LAYOUT]


@pytest.mark.parametrize("edit,message", [
    (lambda p, r: r.update(offset=_heap(p, r["heap"])["bytes"]), "lie past the end of heap"),
    (lambda p, r: r.update(heap=99), "heap 99, which the plan does not list"),
    (lambda p, r: r.update(bytes=2**62), "expected 0 .. 4,398,046,511,104"),
    (lambda p, r: r.update(offset=-r["alignment"]), "negative offset"),
    (lambda p, r: r.update(offset=r["offset"] + 3), "is not aligned to"),
    (lambda p, r: r.update(alignment=3), "not a power of two"),
    (lambda p, r: p["heaps"].append(dict(p["heaps"][0])), "is listed twice"),
])
def test_layout_hazards(plan, edit, message) -> None:
    bad = json.loads(json.dumps(plan))
    edit(bad, _placed(bad))
    assert any(message in m for m in _layout(bad)), _layout(bad)


def test_compiled_plan_has_a_clean_layout(plan) -> None:
    assert _layout(plan) == []


@pytest.mark.parametrize("edit,message", [
    (lambda p: p["passes"][0].update(kind="bogus"), "unknown pass kind 'bogus'"),
    (lambda p: p["passes"][0].update(device=7), "device index 7 out of range: the plan has 1 device"),
    (lambda p: p["passes"][0].update(device="x"), "passes[0].device: expected an integer, got 'x'"),
    (lambda p: p["resources"][0].update(kind="bogus"), "unknown resource kind 'bogus'"),
    (lambda p: p["heaps"][0].update(bytes="x"), "heaps[0].bytes: expected an integer"),
])
def test_malformed_plans(tmp_path: Path, capsys, plan, edit, message) -> None:
    bad = json.loads(json.dumps(plan))
    edit(bad)
    path = tmp_path / "p.json"
    path.write_text(json.dumps(bad, indent=1))
    assert main(["check", str(path)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{path}:") and message in lines[0], lines


@pytest.mark.parametrize("command", [["check"], ["inspect"], ["inspect", "--memory", "--barriers"]])
@pytest.mark.parametrize("text,message", [
    ("[" * 100_000 + "]" * 100_000, "JSON nested deeper than 64 levels"),
    ('{"format": "rgraph-plan/1", "passes": [], "x": ' + "9" * 5000 + "}", "integer out of range"),
    ('{"format": "rgraph-plan/1", "passes": [], "x": NaN}', "'NaN' is not JSON"),
    ('{"format": "rgraph-plan/1", "passes": [], "graph": "\\u001b[31m"}', "contains a control character"),
])
def test_hostile_json(tmp_path: Path, capsys, command, text, message) -> None:
    path = tmp_path / "p.json"
    path.write_text(text)
    assert main([command[0], str(path), *command[1:]]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{path}:1:") and message in lines[0], lines
