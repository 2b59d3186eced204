"""``rgraph inspect`` end to end on the bundled surgery graph, compiled by the real compiler."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest
from report_plans.helpers import inspect

from rgraph.compiler.pipeline import compile_graph
from rgraph.report.barriers import barrier_lines
from rgraph.report.dot import plan_to_dot
from rgraph.report.plan_file import check_plan

BARRIER_LINE = re.compile(
    r"^(before|after) (\w+): (\w+)(\[mips \d+:\d+ layers \d+:\d+\])? "
    r"[A-Z0-9_|]+/[A-Z0-9_|]+(/[A-Z_]+)? -> [A-Z0-9_|]+/[A-Z0-9_|]+(/[A-Z_]+)?"
    r"( (acquire|release) \w+->\w+)?( \(aliases [\w, ]+\))?$"
)
SYNC_LINE = re.compile(r"^(wait before|signal after) \w+: \w+ timeline (>=|=) \d+ \((dst|src) [A-Z0-9_|]+\)$")


@pytest.fixture(scope="module")
def plan():
    return compile_graph("surgery", scene_path=None, params={}, size=(640, 360), policy=None)


def test_compiled_plan_has_the_shape_inspect_reads(plan):
    check_plan(plan, "surgery")
    assert plan["graph"] == "surgery"


def test_summary(capsys, plan):
    code, out, err = inspect(capsys, "surgery", "--size", "640x360")
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].startswith("graph    surgery")
    assert "size     640x360" in lines
    assert f"Schedule ({len(plan['passes'])} passes)" in lines
    for i, p in enumerate(plan["passes"]):
        cells = next(line.split() for line in lines if line.split()[:2] == [str(i), p["name"]])
        assert cells[2:5] == [p["kind"], p["queue"], p["impl"] or "probe"]
    assert any(line.startswith(f"barriers     {plan['stats']['barriers']}") for line in lines)


def test_barrier_lines_cover_every_barrier(capsys, plan):
    code, out, _ = inspect(capsys, "surgery", "--size", "640x360", "--barriers")
    assert code == 0
    body = out.splitlines()[1:-1]
    assert body == barrier_lines(plan)
    for line in body:
        assert BARRIER_LINE.match(line) or SYNC_LINE.match(line), line
    assert sum(line.startswith("before ") for line in body) == plan["stats"]["barriers"]


def test_memory_lists_every_resource_and_heap(capsys, plan):
    code, out, _ = inspect(capsys, "surgery", "--size", "640x360", "--memory")
    assert code == 0
    first_cells = {line.split()[0] for line in out.splitlines() if line.strip()}
    assert {r["name"] for r in plan["resources"]} <= first_cells
    assert {str(h["id"]) for h in plan["heaps"]} <= first_cells


def test_culled_sss_passes_show_their_resources(capsys):
    code, out, _ = inspect(capsys, "surgery", "--scene", "graphs/scenes/cct_no_sss.yaml", "--memory")
    assert code == 0
    rows = {line.split()[0]: line for line in out.splitlines() if line.strip()}
    assert "sss_blur_h" in rows and "sss_blur_v" in rows
    assert "sss_tmp" in rows["sss_blur_h"] + rows["sss_blur_v"]


@pytest.mark.skipif(shutil.which("dot") is None, reason="graphviz is not installed")
def test_dot_renders(plan):
    text = plan_to_dot(plan)
    proc = subprocess.run(["dot", "-Tsvg"], input=text, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert all(p["name"] in proc.stdout for p in plan["passes"])


def test_timeline_and_html(capsys, tmp_path):
    png, page = tmp_path / "t.png", tmp_path / "r.html"
    code, _, err = inspect(capsys, "surgery", "--size", "640x360", "--timeline", str(png), "--html", str(page))
    assert code == 0, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert '<h2 id="memory">' in page.read_text()


def test_a_compiled_plan_file_reads_the_same_as_the_graph(capsys, tmp_path):
    from rgraph.cli import main

    path = tmp_path / "surgery.json"
    assert main(["compile", "surgery", "--size", "640x360", "-o", str(path)]) == 0
    capsys.readouterr()
    for view in ([], ["--barriers"], ["--memory"], ["--dot"]):
        _, from_file, _ = inspect(capsys, str(path), *view)
        _, from_graph, _ = inspect(capsys, "surgery", "--size", "640x360", *view)
        assert from_file == from_graph, view


@pytest.mark.vulkan
def test_culled_passes_show_the_milliseconds_they_saved(capsys, tmp_path):
    """Timings of a real run of the full scene attribute GPU time to what a variant culls."""
    import json

    from rgraph.cli import main

    timings = tmp_path / "full.json"
    assert main(["run", "surgery", "--size", "32x32", "--frames", "2", "--timings", str(timings)]) == 0
    measured = json.loads(timings.read_text())["passes"]
    capsys.readouterr()
    code, out, err = inspect(capsys, "surgery", "--scene", "graphs/scenes/cct_no_sss.yaml", "--size", "32x32",
                             "--timings", str(timings))
    assert code == 0, err
    rows = {line.split()[0]: line.split() for line in out.splitlines() if line.strip()}
    for name in ("sss_blur_h", "sss_blur_v"):
        assert float(rows[name][-1]) == pytest.approx(measured[name], abs=5e-4)
    saved = measured["sss_blur_h"] + measured["sss_blur_v"]
    assert re.search(rf"culling saved .* and {saved:.3f} ms of GPU time per frame", out), out


def test_bad_timings_file_is_a_located_error(capsys, tmp_path):
    bad = tmp_path / "t.json"
    bad.write_text('{"passes": ')
    code, _, err = inspect(capsys, "surgery", "--timings", str(bad))
    assert code == 2 and f"{bad}:1:" in err and "not JSON" in err
