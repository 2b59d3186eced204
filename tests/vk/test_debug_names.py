"""Vulkan objects carry the plan resource's debug name, so validation messages name it."""

from __future__ import annotations

from pathlib import Path

from rgraph.api import compile_for_device
from rgraph.mutate import mutants
from rgraph.vk.executor import execute_plan

GRAPH = """\
rgraph: 1
resources:
  scratch_ao: {kind: image, format: r32_sfloat, size: [16, 16]}
  color:      {kind: image, format: r32_sfloat, size: [16, 16], lifetime: output}
passes:
  make:
    kind: compute
    writes: {scratch_ao: storage_write}
  use:
    kind: compute
    reads: {scratch_ao: sampled}
    writes: {color: storage_write}
outputs: [color]
"""


def test_validation_messages_name_the_resource(tmp_path: Path):
    path = tmp_path / "g.yaml"
    path.write_text(GRAPH)
    plan = compile_for_device(path, None, size=(16, 16))
    clean = execute_plan(plan, validate=True, frames=1, check_data=True)
    assert [str(m) for m in clean.messages] == [] and clean.data_ok
    drops = {m.name: m for m in mutants(plan, ["drop"])}
    dropped = drops.get("drop use/scratch_ao[m0:1 l0:1]")
    assert dropped is not None, sorted(drops)
    result = execute_plan(dropped.plan, validate=True, frames=1, check_data=False)
    text = "\n".join(str(m) for m in result.messages)
    assert result.messages, "dropping the RAW barrier went unnoticed"
    assert "[scratch_ao (frame set 0)]" in text, text  # "VkImage 0x...[scratch_ao (frame set 0)]"
