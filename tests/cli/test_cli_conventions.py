"""Command-line conventions: --version, descriptions, subcommand usage on unknown flags,
one default size, suffix-honouring outputs, validate's extra checks and warnings."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from locations import ROOT

from rgraph import __version__
from rgraph.cli import build_parser, main, subcommand_parser
from rgraph.commands.completion import commands

RGRAPH = [sys.executable, "-m", "rgraph"]


def cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([*RGRAPH, *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_version():
    run = cli("--version")
    assert run.returncode == 0 and run.stdout.strip() == f"rgraph {__version__}"


def test_every_command_has_a_help_and_a_description():
    parser = build_parser()
    for c in commands(parser):
        assert c.help, c.name
        assert subcommand_parser(parser, c.name).description, c.name


def test_unknown_flag_prints_the_subcommands_usage(capsys):
    with pytest.raises(SystemExit) as info:
        main(["validate", "surgery", "--bogus"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: rgraph validate "), err
    assert "rgraph validate: error: unrecognized arguments: --bogus" in err


def test_one_default_size_everywhere():
    parser = build_parser()
    defaults = {}
    for name in ("validate", "compile", "run", "mutate", "sweep"):
        sub = subcommand_parser(parser, name)
        (size,) = [a for a in sub._actions if "--size" in a.option_strings]
        defaults[name] = size.default
    assert set(defaults.values()) == {"640x360"}, defaults
    inspect = subcommand_parser(parser, "inspect")
    (size,) = [a for a in inspect._actions if "--size" in a.option_strings]
    assert "640x360" in size.help


def test_inspect_refuses_timings_of_another_size(tmp_path, capsys):
    timings = tmp_path / "t.json"
    timings.write_text(json.dumps({"device": "x", "size": [320, 180], "passes": {"hbao": 1.0}}))
    assert main(["inspect", "surgery", "--timings", str(timings)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{timings}:1:1: error: timings were measured at 320x180 but the plan is 640x360")
    assert main(["inspect", "surgery", "--size", "320x180", "--timings", str(timings)]) == 0


@pytest.mark.skipif(shutil.which("dot") is None, reason="graphviz not installed")
def test_dot_and_timeline_honour_the_suffix(tmp_path, capsys):
    pdf, png, svg, gv = (tmp_path / f"g.{s}" for s in ("pdf", "png", "svg", "gv"))
    assert main(["inspect", "surgery", "--dot", str(pdf)]) == 0
    assert pdf.read_bytes().startswith(b"%PDF")
    assert main(["inspect", "surgery", "--dot", str(png)]) == 0
    assert png.read_bytes().startswith(b"\x89PNG")
    assert main(["inspect", "surgery", "--dot", str(gv)]) == 0
    assert gv.read_text().startswith('digraph "surgery"')
    assert main(["inspect", "surgery", "--dot", str(tmp_path / "g.jpg")]) == 2
    assert "--dot" in capsys.readouterr().err and not (tmp_path / "g.jpg").exists()
    assert main(["inspect", "surgery", "--timeline", str(svg)]) == 0
    assert b"<svg" in svg.read_bytes()[:400]
    tl_pdf = tmp_path / "t.pdf"
    assert main(["inspect", "surgery", "--timeline", str(tl_pdf)]) == 0
    assert tl_pdf.read_bytes().startswith(b"%PDF")
    assert main(["inspect", "surgery", "--timeline", str(tmp_path / "t.bmp")]) == 2
    assert "cannot draw a timeline as .bmp" in capsys.readouterr().err


ALL_CULLED = """\
rgraph: 1
resources:
  a: {kind: image, format: r8g8b8a8_unorm, size: [8, 8]}
passes:
  p:
    kind: compute
    writes: {a: storage_write}
"""


def test_all_culled_warns_but_validates(tmp_path):
    path = tmp_path / "g.yaml"
    path.write_text(ALL_CULLED)
    run = cli("validate", str(path))
    assert run.returncode == 0, run.stderr
    assert run.stderr == f"{path}:1:1: warning: every pass is culled (reaches no output): the frame does nothing\n"
    doc = json.loads(cli("validate", str(path), "--json").stdout)
    assert doc["ok"] is True and doc["diagnostics"][0]["severity"] == "warning"


def test_validate_checks_impl_names(tmp_path, capsys):
    path = tmp_path / "g.yaml"
    path.write_text(ALL_CULLED.replace("    kind: compute\n", "    kind: compute\n    impl: hbao_upsampel\n")
                    + "outputs: [a]\n")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{path}:7:11: error: no pass implementation named 'hbao_upsampel'; "
                          "did you mean 'hbao_upsample'?"), err


INDIRECT = """\
rgraph: 1
resources:
  args:  {kind: buffer, bytes: 16}
  color: {kind: image, format: r8g8b8a8_unorm, size: [16, 16], lifetime: output}
passes:
  gen:
    kind: compute
    writes: {args: storage_write}
  draw:
    kind: raster
    reads: {args: indirect}
    writes: {color: color_attachment}
outputs: [color]
"""


def test_indirect_minimum_is_checked_at_validate_time(tmp_path, capsys):
    path = tmp_path / "g.yaml"
    path.write_text(INDIRECT)
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{path}:3:32: error: buffer 'args' is used as indirect and pass 'gen' runs the probe"), err
    assert "at least 68 bytes" in err
    path.write_text(INDIRECT.replace("bytes: 16", "bytes: 68"))
    assert main(["validate", str(path)]) == 0


def test_indirect_buffer_at_the_minimum_runs_clean(tmp_path):
    """The minimum validate names is enough: the frame runs under validation with the data
    check (and ``run --json`` reports it as a document)."""
    path = tmp_path / "g.yaml"
    path.write_text(INDIRECT.replace("bytes: 16", "bytes: 68"))
    run = cli("run", str(path), "--size", "16x16", "--validate", "--json")
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert doc["format"] == "rgraph-run/1" and doc["ok"] is True and doc["size"] == [16, 16]
    assert doc["validation"] == {"enabled": True, "messages": []}
    assert doc["data_check"]["ok"] is True and doc["data_check"]["mismatches"] == []
    assert set(doc["timings"]["passes"]) == {"gen", "draw"}


def test_compile_and_inspect_json(tmp_path, capsys):
    plan = tmp_path / "p.json"
    assert main(["compile", "surgery", "--scene", "cct_no_sss", "--json", "-o", str(plan)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["format"] == "rgraph-compile/1" and doc["output"] == str(plan) and "plan" not in doc
    assert [c["pass"] for c in doc["culled"]] == ["sss_blur_h", "sss_blur_v"]
    assert doc["barriers"] == json.loads(plan.read_text())["stats"]["barriers"]
    assert main(["inspect", str(plan), "--json", "--memory", "--barriers"]) == 0
    view = json.loads(capsys.readouterr().out)
    assert view["format"] == "rgraph-inspect/1" and view["scene"] == "cct_no_sss"
    assert len(view["barriers"]) == sum(len(p[k]) for p in json.loads(plan.read_text())["passes"]
                                        for k in ("waits", "barriers", "releases", "signals"))
    assert {r["name"] for r in view["resources"]} >= {"depth", "color"} and view["heaps"]


def test_scene_by_bundled_name(capsys):
    assert main(["validate", "surgery", "--scene", "cct_no_sss"]) == 0
    assert "with scene 'cct_no_sss'" in capsys.readouterr().out
    assert main(["validate", "surgery", "--scene", "cct_nosss"]) == 2
    assert "no such file or bundled scene (bundled: cct, " in capsys.readouterr().err


def test_validate_json_errors_are_objects(tmp_path):
    path = tmp_path / "g.yaml"
    path.write_text("rgraph: 1\npases: {}\n")
    run = cli("validate", str(path), "--json")
    assert run.returncode == 2 and run.stderr == ""
    doc = json.loads(run.stdout)
    assert doc["format"] == "rgraph-validate/1" and doc["ok"] is False
    assert doc["diagnostics"] == [{"severity": "error", "file": str(path), "line": 2, "col": 1,
                                   "message": doc["diagnostics"][0]["message"]}]
    assert doc["diagnostics"][0]["message"].startswith("unknown key 'pases' in the file; did you mean 'passes'?")


def test_check_and_inspect_count_barriers_alike(tmp_path, capsys):
    plan = tmp_path / "plan.json"
    assert main(["compile", "surgery", "-o", str(plan)]) == 0
    capsys.readouterr()
    assert main(["check", str(plan)]) == 0
    check_line = capsys.readouterr().out.strip().splitlines()[-1]
    assert main(["inspect", str(plan), "--json"]) == 0
    stats = json.loads(capsys.readouterr().out)["stats"]
    assert stats["barriers"] == stats["barriers_listed"]
    assert f"{stats['barriers']} barriers + {stats['releases']} queue-family releases" in check_line


def test_culling_saving_counts_each_resource_once(capsys):
    scene = str(ROOT / "graphs" / "scenes" / "cct_no_sss.yaml")
    assert main(["inspect", "surgery", "--scene", scene, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    culled = {c["pass"]: c for c in doc["culled"]}
    assert culled["sss_blur_h"]["resources"] == culled["sss_blur_v"]["resources"] == ["sss_tmp"]
    assert doc["culling_saved"]["bytes"] == culled["sss_blur_h"]["bytes"]
    assert main(["inspect", "surgery", "--scene", scene, "--memory"]) == 0
    assert f"culling saved {culled['sss_blur_h']['bytes'] / 2**20:.1f} MiB" in capsys.readouterr().out
