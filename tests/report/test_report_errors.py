"""Bad plan files and bad flags give ``FILE:LINE:COL: error:`` and exit 2, never a traceback."""

from __future__ import annotations

import json

import pytest
from report_plans.helpers import FORWARD, inspect, load

from rgraph.errors import RGraphError
from rgraph.report.plan_file import check_plan, load_plan


def test_missing_plan_file(capsys, tmp_path):
    path = tmp_path / "nope.json"
    code, out, err = inspect(capsys, str(path))
    assert code == 2 and out == ""
    assert err.strip() == f"{path}:1:1: error: plan file not found"


def test_invalid_json_reports_line_and_column(capsys, tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{\n  "format": "rgraph-plan/1",\n  "passes": [,]\n}\n')
    code, _, err = inspect(capsys, str(path))
    assert code == 2
    assert err.startswith(f"{path}:3:14: error: invalid JSON: Expecting value")
    assert "Traceback" not in err


def test_wrong_format_tag(tmp_path):
    path = tmp_path / "other.json"
    path.write_text(json.dumps({"format": "something-else", "passes": []}))
    with pytest.raises(RGraphError) as info:
        load_plan(path)
    assert str(info.value) == f'{path}:1:12: error: malformed plan: format: expected \'rgraph-plan/1\', got "something-else"'


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda p: p.pop("passes"), "top level: missing key 'passes'"),
        (lambda p: p["passes"][3].pop("name"), "passes[3]: missing key 'name'"),
        (lambda p: p["passes"][3]["barriers"][0].update(src=None), "passes[3].barriers[0].src: expected an object"),
        (lambda p: p["passes"][4]["accesses"][1]["subresource"].update(layers=[3, 1]),
         "passes[4].accesses[1].subresource.layers: expected a half-open range [begin, end]"),
        (lambda p: p["passes"][2]["signals"][0].update(value="1"), "passes[2].signals[0].value: expected an integer"),
        (lambda p: p["resources"][0].update(offset=1.5), "resources[0].offset: expected an integer or null"),
        (lambda p: p["culled"][0].update(resources="sss_tmp"), "culled[0].resources: expected a list"),
        (lambda p: p["stats"].update(barriers=True), "stats.barriers: expected a number"),
    ],
)
def test_malformed_plans_name_the_json_path(mutate, message):
    plan = load(FORWARD)
    mutate(plan)
    with pytest.raises(RGraphError) as info:
        check_plan(plan, "p.json")
    assert str(info.value).startswith(f"p.json:1:1: error: malformed plan: {message}")


def test_fixture_plans_are_well_formed():
    check_plan(load(FORWARD), "forward.json")


def test_compile_flags_are_refused_for_plan_files(capsys):
    code, _, err = inspect(capsys, str(FORWARD), "--scene", "cct", "-p", "a=1")
    assert code == 2
    assert err.strip() == "<command line>:1:1: error: scene, -p only apply when compiling a graph, not to a plan file"


def test_unwritable_outputs(capsys, tmp_path):
    missing = tmp_path / "no" / "dir"
    for flag, name in (("--html", "r.html"), ("--timeline", "t.png"), ("--dot", "g.dot")):
        code, _, err = inspect(capsys, str(FORWARD), flag, str(missing / name))
        assert code == 2, flag
        assert err.startswith(f"{missing / name}:1:1: error: cannot write"), err


def test_graph_arguments_are_compiled_with_the_flags(capsys, monkeypatch):
    """A non-.json argument goes to compile_graph with scene, params, size, policy and profile."""
    import sys
    import types

    calls = []

    def fake_compile_graph(graph, scene_path=None, **options):
        calls.append((graph, scene_path, options))
        return load(FORWARD)

    fake = types.ModuleType("rgraph.compiler.pipeline")
    fake.compile_graph = fake_compile_graph
    monkeypatch.setitem(sys.modules, "rgraph.compiler.pipeline", fake)
    code, out, _ = inspect(capsys, "surgery", "--scene", "cct", "-p", "hbao.directions=4", "-p", "taa=false",
                           "--size", "640x360", "--policy", "dedicated", "--profile", "lavapipe")
    assert code == 0 and "Schedule (8 passes)" in out
    assert calls == [("surgery", "cct", {"params": {"hbao.directions": "4", "taa": "false"}, "policy": "dedicated",
                                         "size": (640, 360), "profile": "lavapipe"})]
    code, _, err = inspect(capsys, "surgery", "-p", "novalue")
    assert code == 2 and err.startswith("<command line>:1:1: error: -p expects name=value")
    calls.clear()
    inspect(capsys, "graphs/surgery.yaml")
    assert calls == [("graphs/surgery.yaml", None, {"params": {}, "policy": None})]


def test_shape_errors_in_a_file_carry_line_and_column(capsys, tmp_path):
    plan = load(FORWARD)
    plan["passes"][3]["barriers"][1]["src"]["stages"] = "COMPUTE_SHADER"
    path = tmp_path / "bad.json"
    text = json.dumps(plan, indent=1, sort_keys=True)
    path.write_text(text)
    code, _, err = inspect(capsys, str(path))
    assert code == 2
    # the line of the offending value in the written text
    line = next(i for i, t in enumerate(text.splitlines(), 1) if '"stages": "COMPUTE_SHADER"' in t)
    col = text.splitlines()[line - 1].index('"COMPUTE_SHADER"') + 1
    assert err.strip() == (f"{path}:{line}:{col}: error: malformed plan: passes[3].barriers[1].src.stages: "
                           "expected a list, got \"COMPUTE_SHADER\"")


def test_partial_plans_render_with_a_warning_from_the_typed_loader(capsys, tmp_path):
    """inspect shows what a partial plan has, and says where the typed loader (rgraph run) refuses it."""
    from report_plans.helpers import MINIMAL

    code, out, err = inspect(capsys, str(MINIMAL))
    assert code == 0 and "Schedule (2 passes)" in out
    assert err.startswith(f"{MINIMAL}:5:5: warning: malformed plan: passes[0]: missing key 'impl'")
    assert err.count("\n") == 1
    plan = load(FORWARD)
    del plan["passes"][3]["barriers"]
    path = tmp_path / "no_barriers.json"
    path.write_text(json.dumps(plan, indent=1))
    code, out, err = inspect(capsys, str(path))
    assert code == 0 and "warning: malformed plan: passes[3]: missing key 'barriers'" in err
    code, _, err = inspect(capsys, str(FORWARD))
    assert code == 0 and err == ""
