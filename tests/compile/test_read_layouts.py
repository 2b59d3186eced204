"""Reads of one image in different usages between two writes share GENERAL and one barrier
(rgraph.compiler.read_layouts) instead of a transition per usage; the frame still runs
clean under validation and the probe's data check on lavapipe."""

from __future__ import annotations

from pathlib import Path

import pytest

from rgraph.check import check_plan
from rgraph.compiler.pipeline import compile_graph

GRAPH = """\
rgraph: 1
resources:
  img:   {kind: image, format: r32_sfloat, size: [16, 16]}
  a:     {kind: image, format: r32_sfloat, size: [16, 16], lifetime: output}
  b:     {kind: image, format: r32_sfloat, size: [16, 16], lifetime: output}
  c:     {kind: image, format: r32_sfloat, size: [16, 16], lifetime: output}
passes:
  make:
    kind: compute
    writes: {img: storage_write}
  sample:
    kind: compute
    reads: {img: sampled}
    writes: {a: storage_write}
  load:
    kind: compute
    reads: {img: storage_read}
    writes: {b: storage_write}
  copy:
    kind: transfer
    reads: {img: transfer_src}
    writes: {c: transfer_dst}
outputs: [a, b, c]
"""


@pytest.fixture
def graph(tmp_path: Path) -> Path:
    path = tmp_path / "g.yaml"
    path.write_text(GRAPH)
    return path


def img_barriers(plan: dict) -> list[tuple[str, str, str]]:
    return [(p["name"], b["src"]["layout"], b["dst"]["layout"]) for p in plan["passes"] for b in p["barriers"]
            if b["resource"] == "img"]


def test_mixed_reads_share_general_and_one_barrier(graph):
    plan = compile_graph(graph, size=(16, 16))
    # sampled + storage_read share GENERAL and one barrier; the copy keeps TRANSFER_SRC_OPTIMAL
    # (from GENERAL the validation layer warns about copy performance)
    assert img_barriers(plan) == [("make", "UNDEFINED", "GENERAL"), ("sample", "GENERAL", "GENERAL"),
                                  ("copy", "GENERAL", "TRANSFER_SRC_OPTIMAL")]
    layouts = {p["name"]: a["layout"] for p in plan["passes"] for a in p["accesses"] if a["resource"] == "img"}
    assert layouts == {"make": "GENERAL", "sample": "GENERAL", "load": "GENERAL", "copy": "TRANSFER_SRC_OPTIMAL"}
    (barrier,) = [b for b in plan["passes"][1]["barriers"] if b["resource"] == "img"]
    assert set(barrier["dst"]["access"]) == {"SHADER_SAMPLED_READ", "SHADER_STORAGE_READ"}
    assert check_plan(plan) == []


def test_reads_in_one_usage_keep_their_optimal_layout(graph):
    plan = compile_graph(Path(graph).write_text(GRAPH.replace("storage_read", "sampled").replace(
        "    reads: {img: transfer_src}\n    writes: {c: transfer_dst}\n", "    reads: {a: transfer_src}\n"
        "    writes: {c: transfer_dst}\n")) and graph, size=(16, 16))
    assert img_barriers(plan) == [("make", "UNDEFINED", "GENERAL"), ("sample", "GENERAL", "SHADER_READ_ONLY_OPTIMAL")]


def test_runs_clean_with_the_data_check(graph):
    from rgraph.api import compile_for_device
    from rgraph.vk.executor import execute_plan

    plan = compile_for_device(graph, None, size=(16, 16))
    result = execute_plan(plan, validate=True, frames=2, check_data=True)
    assert [str(m) for m in result.messages] == []
    assert result.data_ok, result.mismatches
