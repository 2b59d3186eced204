"""compile_graph(..., extra_outputs=...): an intermediate kept as an output and read back."""

from __future__ import annotations

import pytest

from rgraph.compiler.pipeline import compile_graph
from rgraph.errors import RGraphError


def _resource(plan, name):
    return next(r for r in plan["resources"] if r["name"] == name)


def test_extra_output_is_kept_and_read_back():
    plain = compile_graph("surgery", size=(64, 64))
    kept = compile_graph("surgery", size=(64, 64), extra_outputs=["hdr", "color", "hdr"])
    assert plain["outputs"] == ["color"] and kept["outputs"] == ["color", "hdr"]
    assert _resource(plain, "hdr")["lifetime"] == "transient"
    assert _resource(kept, "hdr")["lifetime"] == "output"
    assert [p["name"] for p in kept["passes"]] == [p["name"] for p in plain["passes"]]
    # an output is not aliased: nothing else may share its memory
    hdr = _resource(kept, "hdr")
    for other in kept["resources"]:
        if other["name"] != "hdr" and other["heap"] == hdr["heap"]:
            overlap = other["offset"] < hdr["offset"] + hdr["bytes"] and hdr["offset"] < other["offset"] + other["bytes"]
            assert not overlap, other["name"]


DEAD_END = """\
rgraph: 1
name: dead_end
resources:
  debug: {kind: image, format: r8g8b8a8_unorm, size: output}
  out:   {kind: image, format: r8g8b8a8_unorm, size: output, lifetime: output}
passes:
  visualize:
    kind: compute
    writes: {debug: storage_write}
  shade:
    kind: compute
    writes: {out: storage_write}
outputs: [out]
"""


def test_extra_output_keeps_its_writers_from_culling(tmp_path):
    graph = tmp_path / "dead_end.yaml"
    graph.write_text(DEAD_END)
    plain = compile_graph(graph, size=(16, 16))
    assert [p["name"] for p in plain["passes"]] == ["shade"]
    assert [c["pass"] for c in plain["culled"]] == ["visualize"]
    kept = compile_graph(graph, size=(16, 16), extra_outputs=["debug"])
    assert [p["name"] for p in kept["passes"]] == ["visualize", "shade"] and kept["culled"] == []
    assert _resource(kept, "debug")["lifetime"] == "output"


def test_unknown_extra_output_is_a_located_error():
    with pytest.raises(RGraphError, match="extra output 'hdrr' is not a resource; did you mean 'hdr'"):
        compile_graph("surgery", size=(64, 64), extra_outputs=["hdrr"])
