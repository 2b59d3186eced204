"""`-p views=2` on the bundled surgery graphs and async_overlap (issue 18: every bundled forward
graph renders both eyes in one pass; graphs/clustered.yaml: tests/passes/test_pass_vr_draw.py):
on lavapipe under validation and synchronization validation, each layer of the colour output
equals the mono image rendered with the camera moved to that eye (the whole chain: depth prepass,
HBAO, forward PBR, decals, SSS, composite, bloom, particles, tonemap; shadows and IBL shared), and
the eyes see different pictures."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from locations import ROOT

from rgraph.compiler.pipeline import compile_graph
from rgraph.resources import builtin_passes

builtin_passes()
from rgraph.passes.tonemap_ref import srgb_codes  # noqa: E402

from rgraph.scene.build import load_scene_data  # noqa: E402
from rgraph.scene.instances import eye_offsets  # noqa: E402

SCENE = ROOT / "graphs" / "scenes" / "cct.yaml"
SIZE = (48, 32)
IPD = 0.02  # metres: the camera is 0.3 m from the neck, so the eyes' pictures differ visibly
CAMERA = re.compile(r"^camera: \{position: \[([^\]]*)\], look_at: \[([^\]]*)\],(.*)$", re.M)


def _render(graph: str, scene: Path, params: dict[str, str]) -> np.ndarray:
    from rgraph.vk.errors import VulkanUnavailable
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(graph, scene_path=scene, size=SIZE, params=params)
    try:
        result = execute_plan(plan, validate=True, frames=1, read_outputs=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert [m.text for m in result.messages] == []
    codes = srgb_codes(result.outputs["color"][..., :3])
    return codes if codes.ndim == 4 else codes[None]


def _moved(tmp_path: Path, offset: np.ndarray, eye: int) -> Path:
    """cct.yaml with its camera (position and look_at) moved by ``offset``."""
    text = SCENE.read_text()
    match = CAMERA.search(text)
    assert match, "cct.yaml's camera line changed shape"

    def moved(values: str) -> str:
        return ", ".join(repr(float(v) + float(d)) for v, d in zip(values.split(","), offset, strict=True))

    line = f"camera: {{position: [{moved(match[1])}], look_at: [{moved(match[2])}],{match[3]}"
    path = tmp_path / f"cct_eye{eye}.yaml"
    path.write_text(text[:match.start()] + line + text[match.end():])
    return path


#: per graph, params that keep the run small (async_overlap: a 4096^2 shadow map, 1M particles)
SMALL = {"surgery": {}, "surgery_clustered": {},
         "async_overlap": {"shadow.size": "256", "particles.count": "4096"}}


@pytest.mark.vulkan
@pytest.mark.parametrize("graph", sorted(SMALL))
def test_each_layer_equals_the_mono_image_from_that_eye(graph, tmp_path):
    stereo = _render(graph, SCENE, {**SMALL[graph], "views": "2", "views.ipd": str(IPD)})
    assert stereo.shape[0] == 2
    assert np.abs(stereo[0] - stereo[1]).max() > 20  # the eyes see different pictures
    offsets = eye_offsets(load_scene_data(SCENE, SIZE), 0, 2, IPD)
    for eye, offset in enumerate(offsets):
        mono = _render(graph, _moved(tmp_path, offset, eye), SMALL[graph])
        diff = np.abs(stereo[eye] - mono[0])
        assert mono[0].std() > 5  # a real picture
        assert diff.max() <= 1, f"{graph} eye {eye}: max diff {diff.max()} codes at {np.argwhere(diff > 1)[:5].tolist()}"
