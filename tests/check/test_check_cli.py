"""``rgraph check``: exit codes, report lines, located errors for unreadable plans."""

from __future__ import annotations

import json

import pytest
from plans.check_builder import PLANS, load, without

from rgraph.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(["check", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_clean_plan_exits_0_with_summary(capsys):
    code, out, err = run(capsys, str(PLANS / "basic.json"))
    assert code == 0 and err == ""
    assert out.strip() == f"{PLANS / 'basic.json'}: clean; checked 6 passes, 10 barriers, 5 resources"


def test_hazards_exit_1_one_line_each_then_summary(capsys, tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(without(load("basic"), "update_params", "params")))
    code, out, _ = run(capsys, str(path))
    lines = out.strip().splitlines()
    assert code == 1
    assert lines[:-1] == [
        "pass 5 'update_params' writes 'params' (COMPUTE_SHADER/SHADER_STORAGE_WRITE): WAR hazard: "
        "not ordered after read by pass 2 'gbuffer' (VERTEX_SHADER/UNIFORM_READ)",
        "pass 5 'update_params' writes 'params' (COMPUTE_SHADER/SHADER_STORAGE_WRITE): WAR hazard: "
        "not ordered after read by pass 3 'lighting' (FRAGMENT_SHADER/UNIFORM_READ)",
    ]
    assert lines[-1] == f"{path}: 2 hazards (2 WAR); checked 6 passes, 9 barriers, 5 resources"


def test_json_output(capsys, tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(without(load("subresources"), "mip2", "pyramid")))
    code, out, _ = run(capsys, "--json", str(path))
    assert code == 1
    doc = json.loads(out)
    assert doc["format"] == "rgraph-check/1" and doc["ok"] is False and doc["diagnostics"] == []
    assert doc["checked"] == {"passes": 7, "barriers": 7, "releases": 0, "resources": 2}
    (item,) = doc["hazards"]
    assert item["kind"] == "RAW" and item["pass"] == 5 and item["pass_name"] == "mip2"
    assert item["resource"] == "pyramid" and item["subresource"] == {"mips": [1, 2], "layers": [0, 1]}


def test_missing_file_exits_2(capsys, tmp_path):
    code, _, err = run(capsys, str(tmp_path / "nope.json"))
    assert code == 2
    assert err.strip() == f"{tmp_path / 'nope.json'}:1:1: error: plan file not found"


def test_json_syntax_error_is_located(capsys, tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{\n  "format": "rgraph-plan/1",\n  "passes": [,]\n}\n')
    code, _, err = run(capsys, str(path))
    assert code == 2
    assert err.startswith(f"{path}:3:14: error: invalid JSON")


@pytest.mark.parametrize(("edit", "where", "message"), [
    (lambda p: p["passes"][2]["barriers"][1]["dst"]["stages"].append("FRAGMENT_SHADR"),
     '"FRAGMENT_SHADR"', "unknown stage name 'FRAGMENT_SHADR'"),
    (lambda p: p["passes"][3]["accesses"][1].update(resource="albedoo"),
     '"albedoo"', "unknown resource 'albedoo'"),
    (lambda p: p["passes"][4]["accesses"][0].update(layout="SHADER_READ_ONLY"),
     '"SHADER_READ_ONLY"', "unknown image layout 'SHADER_READ_ONLY'"),
    (lambda p: p["passes"][1].update(index=7),
     '7', "pass index 7 is not its position 1"),
    (lambda p: p["passes"][3]["accesses"][1]["subresource"].update(layers=[0, 9]),
     '[', "range exceeds 'albedo' (1 mips, 1 layers)"),
])
def test_malformed_plan_is_located(capsys, tmp_path, edit, where, message):
    plan = load("basic")
    edit(plan)
    text = json.dumps(plan, indent=1)
    path = tmp_path / "malformed.json"
    path.write_text(text)
    code, out, err = run(capsys, str(path))
    assert code == 2 and out == ""
    location, _, rest = err.strip().partition(": error: ")
    line, col = (int(x) for x in location.rsplit(":", 2)[1:])
    assert message in rest and rest.startswith("malformed plan: passes[")
    assert text.splitlines()[line - 1][col - 1:].startswith(where)


def test_not_an_object(capsys, tmp_path):
    path = tmp_path / "list.json"
    path.write_text("[1, 2]\n")
    code, _, err = run(capsys, str(path))
    assert code == 2 and "malformed plan: top level: expected an object" in err


def test_wrong_format_tag(capsys, tmp_path):
    path = tmp_path / "other.json"
    path.write_text('{"format": "something-else/2", "passes": []}')
    code, _, err = run(capsys, str(path))
    assert code == 2 and f"{path}:1:12: error: malformed plan: format: unsupported plan format" in err
