"""``--devices/--split`` on compile, check, inspect and run; ``rgraph devices``."""

from __future__ import annotations

import json

from locations import ROOT

from rgraph.cli import main

PROBE_GRAPH = str(ROOT / "tests" / "multi_graphs" / "probe_split.yaml")


def test_compile_check_inspect_a_split_plan(tmp_path, capsys):
    out = tmp_path / "plan.json"
    assert main(["compile", PROBE_GRAPH, "--size", "64x64", "--devices", "2", "--split", "sort-first",
                 "-o", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["multi_device"]["devices"] == 2 and {p["device"] for p in doc["passes"]} == {0, 1}
    assert main(["check", str(out)]) == 0
    capsys.readouterr()
    assert main(["inspect", str(out)]) == 0
    text = capsys.readouterr().out
    assert "schedule per device" in text and "lit.download@1" in text and "d1.graphics >= 1" in text
    for p in doc["passes"]:  # drop the cross-device wait: check must refuse it
        p["waits"] = [w for w in p["waits"] if "device" not in w]
    out.write_text(json.dumps(doc))
    assert main(["check", str(out)]) == 1


def test_split_needs_a_mode_and_valid_indices(capsys):
    assert main(["compile", PROBE_GRAPH, "--devices", "2"]) == 2
    assert main(["run", PROBE_GRAPH, "--devices", "0,-1", "--split", "sort-last"]) == 2
    err = capsys.readouterr().err
    assert err.count("error:") == 2 and "Traceback" not in err


def test_devices_lists_at_least_one(capsys):
    assert main(["devices"]) == 0
    assert capsys.readouterr().out.startswith("0: ")


def test_run_on_two_logical_devices_validated(capsys, tmp_path):
    timings = tmp_path / "t.json"
    assert main(["run", PROBE_GRAPH, "--size", "64x64", "--devices", "0,0", "--split", "sort-last", "--validate",
                 "--timings", str(timings)]) == 0
    err = capsys.readouterr().err
    assert "0 validation message(s)" in err and "data check ok against the one-device plan" in err
    assert len(json.loads(timings.read_text())["device_ms"]) == 2


def test_run_staged_pipelined_and_dynamic(capsys, tmp_path):
    timings = tmp_path / "t.json"
    assert main(["run", PROBE_GRAPH, "--size", "64x64", "--devices", "0,0", "--split", "sort-first", "--validate",
                 "--transfer", "staged", "--pipelined", "--frames", "3", "--timings", str(timings)]) == 0
    err = capsys.readouterr().err
    assert "(staged transfer)" in err and "0 validation message(s)" in err and "data check ok" in err
    assert json.loads(timings.read_text())["transfer"] == "staged"
    assert main(["run", PROBE_GRAPH, "--size", "64x64", "--devices", "0,0", "--split", "sort-first", "--validate",
                 "--balance", "dynamic", "--frames", "4"]) == 0
    err = capsys.readouterr().err
    assert "plan load(s) for 4 frame(s)" in err and "(shared transfer)" in err and "data check ok" in err
