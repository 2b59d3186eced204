"""surgery_clustered.yaml: the surgery graph whose forward_pbr shades froxel lists. On the cct
scene with 200 extra generated point lights and a spot light, the clustered image equals
lighting.mode=all_lights and plain surgery.yaml (every light through the uniform block) within
one 8-bit code, under validation."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT

from rgraph.compiler.pipeline import compile_graph

SIZE = (64, 36)
EXTRA = """  - {generate: point, count: 200, seed: 11, bounds: [[-0.15, -0.1, 0.0], [0.15, 0.15, 0.2]], radius: [0.01, 0.08],
     intensity: [0.002, 0.01]}
  - {type: spot, position: [0.0, 0.05, 0.2], direction: [0, -0.3, -1], cone: [8, 14], radius: 0.5, intensity: 0.3}
"""


def _run(graph: str, scene, params: dict[str, str]):
    from rgraph.passes.tonemap_ref import srgb_codes

    from rgraph.vk.executor import execute_plan

    plan = compile_graph(graph, scene_path=scene, size=SIZE, params={"shadow.size": "256", **params})
    result = execute_plan(plan, validate=True, frames=1, read_outputs=True)
    assert [m.text for m in result.messages] == []
    return srgb_codes(result.outputs["color"][..., :3]), result.outputs


@pytest.mark.vulkan
def test_surgery_clustered_equals_every_light(tmp_path):
    text = (ROOT / "graphs" / "scenes" / "cct.yaml").read_text()
    scene = tmp_path / "cct_many.yaml"
    scene.write_text(text.replace("materials:\n", EXTRA + "materials:\n", 1))
    small = {"clusters.tile": "16", "clusters.slices": "8"}
    clustered, out = _run("surgery_clustered", scene, small)
    every, _ = _run("surgery_clustered", scene, {**small, "lighting.mode": "all_lights"})
    plain, _ = _run("surgery", scene, {})
    from rgraph.passes.cluster_report import stats_of

    s = stats_of(out["cluster_stats"])
    assert s["overflowed_froxels"] == 0 and 0 < s["references"] < 0.5 * 204 * 4 * 2 * 8  # lists, not every light
    assert np.abs(clustered - every).max() <= 1 and np.abs(clustered - plain).max() <= 1
    base, _ = _run("surgery", ROOT / "graphs" / "scenes" / "cct.yaml", {})
    assert np.abs(plain - base).max() > 10  # the extra lights are visible
