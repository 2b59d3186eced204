"""Sweep settings (knob parsing, one-at-a-time and grid expansion, extremes) and Pareto fronts."""

from __future__ import annotations

import pytest
from locations import TESTS

from rgraph.errors import RGraphError
from rgraph.resources import resolve_graph
from rgraph.spec.loader import load_graph
from rgraph.sweep.pareto import pareto_front
from rgraph.sweep.runner import extreme_labels
from rgraph.sweep.settings import (
    Knob,
    expand,
    numeric_key,
    params_key,
    parse_assignments,
    parse_knob,
    resolved,
)

GRAPH = TESTS / "sweep_fixtures" / "graph.yaml"


@pytest.fixture(scope="module")
def surgery():
    return load_graph(resolve_graph("surgery"))


def test_parse_knob():
    assert parse_knob(" hbao.directions = 2, 4,8 ") == Knob("hbao.directions", ("2", "4", "8"))
    for bad in ("hbao.directions", "=2,4", "hbao.directions=", "hbao.directions=2,,4"):
        with pytest.raises(RGraphError, match="--knob expects"):
            parse_knob(bad)
    with pytest.raises(RGraphError, match="listed twice"):
        parse_knob("a=1,2,1")


def test_parse_assignments():
    assert parse_assignments(["a=1", "b = x"], "--reference") == {"a": "1", "b": "x"}
    with pytest.raises(RGraphError, match="given twice"):
        parse_assignments(["a=1", "a=2"], "--reference")
    with pytest.raises(RGraphError, match="--reference expects name=value"):
        parse_assignments(["a"], "--reference")


def test_one_knob_at_a_time(surgery):
    knobs = [parse_knob("hbao.directions=2,16"), parse_knob("sss.samples=11,25")]
    settings = expand(surgery, knobs, base={"shadow.size": "512"}, reference={"hbao.directions": "32"})
    assert [s.label for s in settings] == ["reference", "default", "hbao.directions=2", "hbao.directions=16",
                                           "sss.samples=11", "sss.samples=25"]
    assert settings[0].overrides == {"shadow.size": "512", "hbao.directions": "32"}
    assert settings[1].overrides == {"shadow.size": "512"}
    assert settings[3].overrides == {"shadow.size": "512", "hbao.directions": "16"}
    assert settings[3].varied == {"hbao.directions": "16"} and settings[3].slug == "hbao.directions=16"
    assert resolved(surgery, settings[4].overrides)["sss.samples"] == 11


def test_grid(surgery):
    knobs = [parse_knob("hbao.directions=2,16"), parse_knob("sss.samples=11,17,25")]
    settings = expand(surgery, knobs, grid=True)
    combos = [s for s in settings if s.role == "knob"]
    assert len(combos) == 6
    assert combos[0].label == "hbao.directions=2,sss.samples=11"
    assert combos[0].slug == "hbao.directions=2_sss.samples=11"
    assert extreme_labels(settings, knobs, grid=True) == ["hbao.directions=2,sss.samples=11",
                                                          "hbao.directions=16,sss.samples=25"]


def test_settings_equal_to_the_defaults_share_a_key(surgery):
    settings = expand(surgery, [parse_knob("hbao.directions=8,0x8,4")])
    keys = [params_key(resolved(surgery, s.overrides)) for s in settings]
    assert keys[0] == keys[1] == keys[2] == keys[3]  # reference, default, 8 and 0x8 render once
    assert keys[4] != keys[0]


def test_extremes_are_lowest_and_highest_by_value(surgery):
    knobs = [parse_knob("hbao.directions=8,16,2,4")]
    settings = expand(surgery, knobs)
    assert extreme_labels(settings, knobs, grid=False) == ["hbao.directions=2", "hbao.directions=16"]
    assert sorted(["10", "9", "x", "1.5"], key=numeric_key) == ["1.5", "9", "10", "x"]


def test_bad_settings_fail_before_rendering(surgery):
    with pytest.raises(RGraphError, match="unknown param 'hbao.direction'; did you mean 'hbao.directions'"):
        expand(surgery, [parse_knob("hbao.direction=2")])
    with pytest.raises(RGraphError, match="expects an integer, got 'many'"):
        expand(surgery, [parse_knob("hbao.directions=2,many")])
    with pytest.raises(RGraphError, match="unknown param 'nope'"):
        expand(surgery, [parse_knob("hbao.directions=2")], reference={"nope": "1"})
    with pytest.raises(RGraphError, match="both a --knob and a -p"):
        expand(surgery, [parse_knob("hbao.directions=2")], base={"hbao.directions": "4"})
    with pytest.raises(RGraphError, match="given twice"):
        expand(surgery, [parse_knob("hbao.directions=2"), parse_knob("hbao.directions=4")])
    with pytest.raises(RGraphError, match="at least one --knob"):
        expand(surgery, [])
    with pytest.raises(RGraphError, match="--grid gives"):
        expand(surgery, [parse_knob("shadow.size=" + ",".join(str(i) for i in range(1, 41))),
                         parse_knob("hbao.steps=" + ",".join(str(i) for i in range(1, 41)))], grid=True)


def test_fixture_graph_loads():
    source = load_graph(GRAPH)
    assert resolved(source, {"aa.samples": "4"})["aa.samples"] == 4


def test_pareto_front():
    ms = [1.0, 2.0, 3.0, 2.5, 4.0, None]
    err = [0.5, 0.2, 0.2, 0.1, 0.0, 0.0]
    assert pareto_front(ms, err) == [0, 1, 3, 4]  # 2 is dominated by 1 (slower, same error)
    psnr = [20.0, 30.0, 25.0, float("inf")]
    assert pareto_front([1.0, 2.0, 3.0, 4.0], psnr, lower_is_better=False) == [0, 1, 3]
    assert pareto_front([1.0, 1.0], [0.3, 0.3]) == [0, 1]  # equal points dominate neither
    assert pareto_front([1.0, float("nan")], [0.1, 0.0]) == [0]
    assert pareto_front([], []) == []
