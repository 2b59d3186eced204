"""Arguments and outputs are checked before any work (issue 14): exit 2 with one located line."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from rgraph.cli import main
from rgraph.commands.outputs import check_output_file
from rgraph.errors import RGraphError
from rgraph.impl import Param, param_problems

GRAPH = ("rgraph: 1\nresources:\n  color: {kind: image, format: r8g8b8a8_unorm, size: output, lifetime: output}\n"
         "passes:\n  p: {kind: raster, writes: {color: color_attachment}}\noutputs: [color]\n")


@pytest.fixture
def graph(tmp_path: Path) -> Path:
    path = tmp_path / "g.yaml"
    path.write_text(GRAPH)
    return path


@pytest.mark.parametrize("target", ["missing/x", "DIR", "/dev/full", "missing/"])
def test_unwritable_outputs_are_refused_before_the_work(tmp_path: Path, target: str) -> None:
    target = str(tmp_path) if target == "DIR" else f"{tmp_path}/{target}" if target.startswith("missing") else target
    with pytest.raises(RGraphError) as info:
        check_output_file(target, "--out")
    assert str(info.value).startswith("<command line>:1:1: error: --out: ")
    assert not os.path.exists(tmp_path / "missing")


@pytest.mark.parametrize("flag", ["--out", "--timings"])
def test_run_refuses_a_missing_folder_without_opening_the_device(graph: Path, capsys, flag: str) -> None:
    assert main(["run", str(graph), "--size", "8x8", flag, str(graph.parent / "no" / "x")]) == 2
    err = capsys.readouterr().err
    assert f"error: {flag}: cannot write" in err and "device 0" not in err


def test_compile_refuses_dev_full(graph: Path, capsys) -> None:
    assert main(["compile", str(graph), "-o", "/dev/full"]) == 2
    assert "error: -o: cannot write '/dev/full'" in capsys.readouterr().err


@pytest.mark.parametrize("frames", ["1e20", "0", "100000000000000000000", "-3"])
def test_frames_are_bounded(graph: Path, capsys, frames: str) -> None:
    with pytest.raises(SystemExit) as info:
        main(["run", str(graph), "--frames", frames])
    assert info.value.code == 2
    assert "error: argument --frames: expected an integer in 1..1,000,000" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["run", "sweep"])
@pytest.mark.parametrize("seconds", ["-1", "nan", "inf", "1e9", "soon"])
def test_warmup_is_bounded(graph: Path, capsys, command: str, seconds: str) -> None:
    extra = ["--knob", "a=1", "-o", str(graph.parent / "o")] if command == "sweep" else []
    with pytest.raises(SystemExit) as info:
        main([command, str(graph), "--warmup", seconds, *extra])
    assert info.value.code == 2
    assert "error: argument --warmup: expected seconds in 0..600" in capsys.readouterr().err


@pytest.mark.parametrize("param,message", [
    ("hbao.directions=0", "param 'hbao.directions' (read by pass 'hbao_downsample', impl 'hbao_downsample') must "
                          "be in 1..64, got 0"),
    ("sss.kernel=evil", "param 'sss.kernel' (read by pass 'sss_blur_h', impl 'sss_blur') must be one of "
                        "separable, 2d, got 'evil'"),
])
def test_pass_params_are_checked_before_the_device_opens(capsys, param: str, message: str) -> None:
    assert main(["run", "surgery", "--size", "16x16", "-p", param]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"<command line>:1:1: error: {message}"]


def test_param_schema_checks() -> None:
    assert Param(int, 1, 8).problem(0) == "must be in 1..8, got 0"
    assert Param(int, 1, 8).problem(2.5) == "must be an integer in 1..8, got 2.5"
    assert Param(float, 0, 1).problem(float("nan")) == "must be a finite number in 0..1, got nan"
    assert Param(str, choices=("h", "v")).problem("z") == "must be one of h, v, got 'z'"
    assert Param(bool).problem(1) is None and Param(bool).problem("yes") is not None
    assert Param(int, 1, 8).problem(4) is None


def test_an_output_param_set_by_the_graph_file_is_refused() -> None:
    """A graph may not name files to write: alloc.report must come from the command line."""
    from rgraph.compiler.pipeline import compile_graph

    plan = compile_graph("allocator_lines", size=(16, 16), params={"alloc.report": "/tmp/anything.json"})
    problems = param_problems(plan, user_params={})
    assert [name for name, _ in problems] == ["alloc.report"]
    assert "was not given on the command line" in problems[0][1]
    assert param_problems(plan, user_params={"alloc.report": "/tmp/anything.json"}) == []


def test_validate_ok_line_escapes_names(tmp_path: Path, capsys) -> None:
    path = tmp_path / "g.yaml"
    path.write_text("rgraph: 1\nname: \"a\u202eb\"\n")
    assert main(["validate", str(path)]) == 2  # a bidi override is refused where it is written
    assert "control character U+202E" in capsys.readouterr().err


def test_a_plans_scene_source_stays_inside_its_folder_or_the_bundled_graphs(tmp_path: Path, capsys) -> None:
    import json

    from rgraph.compiler.pipeline import compile_graph
    from rgraph.spec.paths import allow_outside, check_plan_scene

    plan = compile_graph("surgery", size=(16, 16))
    check_plan_scene(plan, tmp_path / "p.json")  # the bundled scene
    (tmp_path / "s.yaml").write_text("scene: 1\n")
    check_plan_scene({**plan, "scene_source": str(tmp_path / "s.yaml")}, tmp_path / "p.json")
    evil = {**plan, "scene_source": "/etc/hostname"}
    with pytest.raises(RGraphError, match="lies outside the plan's folder"):
        check_plan_scene(evil, tmp_path / "p.json")
    with allow_outside():
        check_plan_scene(evil, tmp_path / "p.json")
    path = tmp_path / "p.json"
    path.write_text(json.dumps(evil))
    assert main(["run", str(path)]) == 2
    assert "scene_source '/etc/hostname' lies outside" in capsys.readouterr().err
