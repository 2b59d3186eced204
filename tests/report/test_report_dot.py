"""Pass dependencies from accesses, and the DOT view: deterministic, valid, renderable."""

from __future__ import annotations

import shutil
import subprocess

import pytest
from report_plans.helpers import FORWARD, MINIMAL, inspect, load

from rgraph.report.deps import Edge, SemaphoreEdge, dependency_edges, semaphore_edges
from rgraph.report.dot import plan_to_dot

needs_dot = pytest.mark.skipif(shutil.which("dot") is None, reason="graphviz is not installed")


def access(resource, write, layers=(0, 1), usage=None, access_flags=()):
    return {
        "resource": resource,
        "subresource": None if layers is None else {"mips": [0, 1], "layers": list(layers)},
        "usage": usage or ("storage_write" if write else "sampled"),
        "stages": ["COMPUTE_SHADER"],
        "access": list(access_flags),
        "layout": "GENERAL",
        "write": write,
    }


def plan_of(*passes):
    return {
        "format": "rgraph-plan/1",
        "graph": "t",
        "passes": [{"name": f"p{i}", "index": i, "accesses": list(a)} for i, a in enumerate(passes)],
    }


def test_reads_depend_on_every_writer_of_an_overlapping_subresource():
    plan = plan_of(
        [access("arr", True, (0, 2))],  # p0 writes layers 0-1
        [access("arr", True, (2, 4))],  # p1 writes layers 2-3
        [access("arr", False, (0, 4))],  # p2 reads all: after p0 and p1
        [access("arr", False, (2, 3))],  # p3 reads layer 2: after p1 only
        [access("arr", True, (0, 1))],  # p4 overwrites layer 0: after p0 (WAW) and p2 (WAR), not p3
    )
    assert dependency_edges(plan) == [
        Edge(0, 2, "RAW", ("arr",)),
        Edge(0, 4, "WAW", ("arr",)),
        Edge(1, 2, "RAW", ("arr",)),
        Edge(1, 3, "RAW", ("arr",)),
        Edge(2, 4, "WAR", ("arr",)),
    ]


def test_read_modify_write_is_raw_and_a_pass_never_depends_on_itself():
    depth_rw = dict(usage="depth_attachment", access_flags=("DEPTH_STENCIL_ATTACHMENT_READ",
                                                           "DEPTH_STENCIL_ATTACHMENT_WRITE"))
    plan = plan_of(
        [access("depth", True, **depth_rw), access("buf", True, layers=None)],
        [access("depth", True, **depth_rw), access("buf", False, layers=None), access("buf", False, layers=None)],
        [access("buf", True, layers=None)],
    )
    assert dependency_edges(plan) == [
        Edge(0, 1, "RAW", ("buf", "depth")),
        Edge(0, 2, "WAW", ("buf",)),
        Edge(1, 2, "WAR", ("buf",)),
    ]


def test_write_flag_falls_back_to_the_usage():
    a = access("img", True)
    del a["write"]
    b = access("img", False)
    del b["write"]
    assert dependency_edges(plan_of([a], [b])) == [Edge(0, 1, "RAW", ("img",))]


def test_forward_plan_edges():
    plan = load(FORWARD)
    names = [p["name"] for p in plan["passes"]]
    edges = {(names[e.src], names[e.dst], e.kind, e.resources) for e in dependency_edges(plan)}
    assert ("depth_prepass", "hbao", "RAW", ("depth",)) in edges
    assert ("hbao", "lighting", "RAW", ("ao",)) in edges
    assert ("light_cull", "lighting", "RAW", ("lights",)) in edges
    assert ("tonemap", "history_copy", "WAR", ("history",)) in edges
    # history is persistent: tonemap reads last frame's copy, so nothing this frame precedes it
    assert not any(dst == "tonemap" and res == ("history",) for _, dst, _, res in edges)
    assert semaphore_edges(plan) == [SemaphoreEdge(2, 3, "graphics", 1), SemaphoreEdge(3, 4, "compute", 1)]


def test_dot_text_is_deterministic_and_styled(capsys):
    plan = load(FORWARD)
    first = plan_to_dot(plan)
    assert first == plan_to_dot(load(FORWARD))
    code, out, _ = inspect(capsys, str(FORWARD), "--dot")
    assert code == 0 and out == first
    _, again, _ = inspect(capsys, str(FORWARD), "--dot")
    assert again.encode() == out.encode()
    lines = first.splitlines()
    assert lines[0] == 'digraph "forward" {'
    assert '  p3 [label="3: hbao\\ncompute on compute\\nhbao", fillcolor="#fbe8c8"];' in lines
    assert ('  c0 [label="sss_blur_h\\nculled", tooltip="scene has no sss_materials", '
            'style="rounded,dashed", color="#999999", fontcolor="#999999"];') in lines
    assert '  p3 -> p4 [label="RAW ao", style=solid, color="#303030"];' in lines
    assert '  p6 -> p7 [label="WAR history", style=dashed, color="#2a6fb0"];' in lines
    assert any(line.startswith('  p2 -> p3 [label="graphics >= 1", style=bold') for line in lines)
    # nodes in executed order
    node_lines = [line for line in lines if line.startswith("  p") and "->" not in line]
    assert [line.split()[0] for line in node_lines] == [f"p{i}" for i in range(8)]


def test_dot_quotes_odd_names():
    plan = plan_of([access('we"ird\\name', True)], [access('we"ird\\name', False)])
    plan["culled"] = [{"pass": "x", "reason": 'says "no"'}]
    text = plan_to_dot(plan)
    assert 'label="RAW we\\"ird\\\\name"' in text
    assert 'tooltip="says \\"no\\""' in text


@needs_dot
@pytest.mark.parametrize("fixture", [FORWARD, MINIMAL])
def test_dot_is_valid_for_graphviz(fixture):
    proc = subprocess.run(["dot", "-Tsvg"], input=plan_to_dot(load(fixture)), capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert "<svg" in proc.stdout
    assert all(p["name"] in proc.stdout for p in load(fixture)["passes"])


@needs_dot
def test_dot_to_svg_and_dot_files(capsys, tmp_path):
    svg, dot = tmp_path / "g.svg", tmp_path / "g.dot"
    code, _, err = inspect(capsys, str(FORWARD), "--dot", str(svg))
    assert code == 0 and err.strip() == f"wrote {svg}"
    text = svg.read_text()
    assert "<svg" in text and "lighting" in text and "digraph" not in text
    code, out, _ = inspect(capsys, str(FORWARD), "--dot", str(dot))
    assert code == 0
    assert dot.read_text() == plan_to_dot(load(FORWARD))
    assert "Schedule (8 passes)" in out  # a file output leaves the summary on stdout
