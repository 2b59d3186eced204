"""Repeated passes (``for:``), expressions in resource keys, and the mip/layer selector axes."""

from __future__ import annotations

from pathlib import Path

import pytest

from rgraph.compiler.pipeline import compile_graph, frontend
from rgraph.errors import RGraphError

CHAIN = """\
rgraph: 1
name: chain
params: {levels: 5}
resources:
  src:   {kind: image, format: r16g16b16a16_sfloat, size: [64, 64]}
  pyr:   {kind: image, format: r16g16b16a16_sfloat, size: [64, 64], mips: "${params.levels}"}
  color: {kind: image, format: r16g16b16a16_sfloat, size: [64, 64], lifetime: output}
passes:
  fill:
    kind: compute
    writes: {src: storage_write, "pyr[mip=0]": storage_write}
  down_${i}:
    for: {i: [1, "${params.levels}"]}
    kind: compute
    reads: {"pyr[mip=${i - 1}]": sampled}
    writes:
      pyr[mip=${i}]: storage_write
  up_${params.levels - 1 - j}:
    for: {j: [1, "${params.levels}"]}
    kind: compute
    reads: {"pyr[mip=${params.levels - j}]": sampled}
    writes: {"pyr[mip=${params.levels - j - 1}]": storage_rw}
  resolve:
    kind: compute
    reads: {src: sampled, "pyr[mip=0]": sampled}
    writes: {color: storage_write}
outputs: [color]
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "g.yaml"
    path.write_text(text)
    return path


def test_chain_expands_in_declaration_order(tmp_path):
    spec = frontend(write(tmp_path, CHAIN)).spec
    names = [p.name for p in spec.passes]
    assert names == ["fill", "down_1", "down_2", "down_3", "down_4", "up_3", "up_2", "up_1", "up_0", "resolve"]
    down2 = spec.passes[2]
    assert [(a.usage, a.mips) for a in down2.accesses] == [("sampled", (1, 2)), ("storage_write", (2, 3))]
    up0 = spec.passes[8]
    assert [(a.usage, a.mips) for a in up0.accesses] == [("sampled", (1, 2)), ("storage_rw", (0, 1))]


def test_levels_param_changes_the_chain(tmp_path):
    spec = frontend(write(tmp_path, CHAIN), params={"levels": "3"}).spec
    assert [p.name for p in spec.passes] == ["fill", "down_1", "down_2", "up_1", "up_0", "resolve"]


def test_chain_compiles_and_checks_clean(tmp_path):
    from rgraph.check import check_plan

    plan = compile_graph(write(tmp_path, CHAIN), size=(64, 64))
    assert len(plan["passes"]) == 10
    assert check_plan(plan) == []


def test_chain_runs_clean_under_validation_with_the_data_check(tmp_path):
    """End to end on lavapipe: the expanded chain runs with the probe, no validation message,
    and the read-back data equals the CPU simulation of the graph."""
    from rgraph.api import compile_for_device
    from rgraph.vk.executor import execute_plan

    plan = compile_for_device(write(tmp_path, CHAIN), None, size=(64, 64))
    result = execute_plan(plan, validate=True, frames=2, check_data=True)
    assert [str(m) for m in result.messages] == []
    assert result.data_ok, result.mismatches


@pytest.mark.parametrize(("old", "new", "where", "message"), [
    ("    for: {i: [1, \"${params.levels}\"]}\n", "    for: {i: [1], k: [2, 3]}\n", (13, 10),
     "'for' takes exactly one variable"),
    ("    for: {i: [1, \"${params.levels}\"]}\n", "    for: {i: [1]}\n", (13, 14), "takes [first, stop]"),
    ("    for: {i: [1, \"${params.levels}\"]}\n", "    for: {i: [1, \"${params.level}\"]}\n", (13, 21),
     "unknown name 'params.level'"),
    ("  down_${i}:\n", "  down:\n", (12, 3), "needs '${i}' in its name"),
    ("    reads: {\"pyr[mip=${i - 1}]\": sampled}\n", "    reads: {\"pyr[mip=${k - 1}]\": sampled}\n", (15, 13),
     "unknown name 'k'"),
    ("    reads: {\"pyr[mip=${i - 1}]\": sampled}\n", "    reads: {\"pyr[mip=${i + 1}]\": sampled}\n", (15, 13),
     "mip range 5:6 is outside 'pyr', which has 5 mips"),
    ("  up_${params.levels - 1 - j}:\n", "  down_${5 - j}:\n", (18, 3), "pass name 'down_4' (from 'down_${5 - j}')"),
])
def test_errors_are_located(tmp_path, old, new, where, message):
    assert old in CHAIN
    with pytest.raises(RGraphError) as info:
        frontend(write(tmp_path, CHAIN.replace(old, new, 1)))
    diag = info.value.first
    assert message in diag.message
    assert (diag.location.line, diag.location.col) == where, str(diag)


@pytest.mark.parametrize("axis", ["mips", "layers"])
def test_plural_axis_is_an_error(tmp_path, axis):
    text = CHAIN.replace('"pyr[mip=0]": storage_write}', f'"pyr[{axis}=0]": storage_write}}', 1)
    with pytest.raises(RGraphError) as info:
        frontend(write(tmp_path, text))
    assert f"the axis is '{axis[:-1]}'" in info.value.first.message


def test_expression_in_a_plain_selector(tmp_path):
    text = CHAIN.replace('"pyr[mip=0]": sampled}', '"pyr[mip=${params.levels - 5}]": sampled}', 1)
    spec = frontend(write(tmp_path, text)).spec
    assert spec.passes[-1].accesses[1].mips == (0, 1)
