"""One command buffer per frame (issue 18, session 11) on lavapipe under validation +
synchronization validation.

Without validation the lowering cuts batches only where a semaphore is needed
(``rgraph.vk.lower.batches.make_batches``, cuts ``queue``): on one VkQueue the clustered
graph's frame is one command buffer in one VkSubmitInfo2, where the plan's cuts gave two.
Validation normally records one batch per pass (messages name the pass); here that is turned
off so the layer checks the merged command buffer itself: zero messages, and every output of
two frames (both frame-in-flight sets) equals the per-pass run's bit for bit, for the skinned
scene and for the lighting test scene.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT
from skinning_helpers import SCENE, SIZE

GRAPH = ROOT / "graphs" / "clustered.yaml"
PARAMS = {"clusters.tile": "16", "clusters.slices": "4", "draw.mode": "gpu"}


def _run(scene_path, one_batch: bool, monkeypatch) -> tuple[int, dict]:
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk import executor as executor_module
    from rgraph.vk.executor import execute_plan
    from rgraph.vk.runtime import submits

    batches: list[int] = []
    real = submits.build

    def spy(ex):
        batches.append(len(ex.recording.batches))
        return real(ex)

    if one_batch:  # the unvalidated lowering, validated
        monkeypatch.setattr(executor_module, "submit_per_pass", lambda _validate: False)
        monkeypatch.setattr(submits, "submit_per_pass", lambda _validate: False)
    monkeypatch.setattr(submits, "build", spy)
    plan = compile_graph(GRAPH, scene_path=scene_path, size=SIZE, params=PARAMS)
    result = execute_plan(plan, validate=True, frames=2, read_outputs=True)
    monkeypatch.undo()
    assert [m.text for m in result.messages] == []
    return batches[0], result.outputs


@pytest.mark.vulkan
@pytest.mark.parametrize("scene", ["skinned", "lighting"])
def test_one_command_buffer_per_frame_is_clean_and_renders_the_same(tmp_path, monkeypatch, scene):
    if scene == "skinned":
        path = tmp_path / "skin_case.yaml"
        path.write_text(SCENE.replace("BONES", "16"))
    else:
        path = ROOT / "graphs" / "scenes" / "lighting_test.yaml"
    per_pass_batches, per_pass = _run(path, False, monkeypatch)
    one_batches, one = _run(path, True, monkeypatch)
    assert one_batches == 1 < per_pass_batches
    assert per_pass.keys() == one.keys() and per_pass
    for name in per_pass:
        assert np.array_equal(np.asarray(per_pass[name]), np.asarray(one[name])), name
