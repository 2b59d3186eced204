"""Shared by the clustered-lighting tests: scenes written on the fly, graphs/clustered.yaml with
chosen intermediates as outputs, and one validated run of it (zero messages asserted)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from locations import ROOT
from ruamel.yaml import YAML

GRAPH = ROOT / "graphs" / "clustered.yaml"
BASE_MESHES = """materials:
  box:   {base_color: [0.7, 0.7, 0.72], roughness: 0.4, metallic: 0}
  floor: {base_color: [0.5, 0.5, 0.5], roughness: 0.7, metallic: 0}
meshes:
  - {shape: plane, params: {size: [60, 60], subdivisions: 1}, material: floor}
  - {shape: box, params: {size: [1, 1, 1]}, material: box, position: [0, 0.5, 0], instances: {grid: [3, 1, 3], spacing: 3}}
"""
CAMERA = "camera: {position: [0, 3, 10], look_at: [0, 0, 0], fov_y: 60, near: 0.1}\n"


def scene_file(tmp_path: Path, lights: str, *, camera: str = CAMERA, meshes: str = BASE_MESHES,
               name: str = "case") -> Path:
    p = tmp_path / f"{name}.yaml"
    p.write_text(f"scene: 1\nname: {name}\n{camera}lights:\n{lights or '  []'}\n{meshes}")
    return p


def graph_with_outputs(tmp_path: Path, names: tuple[str, ...]) -> Path:
    """graphs/clustered.yaml with ``names`` made outputs (to read intermediates back)."""
    y = YAML()
    doc = y.load(GRAPH.read_text())
    for n in names:
        doc["resources"][n]["lifetime"] = "output"
    doc["outputs"] = list(doc["outputs"]) + [n for n in names if n not in doc["outputs"]]
    doc.pop("scene", None)
    p = tmp_path / "clustered_outputs.yaml"
    with p.open("w") as f:
        y.dump(doc, f)
    return p


def render(scene: Path, *, size=(64, 48), mode: str = "clustered", params: dict | None = None,
           graph: Path = GRAPH, frames: int = 1):
    """(plan, outputs) of one validated run; asserts zero validation messages."""
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(graph, scene_path=scene, size=size,
                         params={"lighting.mode": mode, "clusters.tile": "8", "clusters.slices": "12",
                                 **(params or {})})
    result = execute_plan(plan, validate=True, frames=frames, read_outputs=True)
    assert [m.text for m in result.messages] == []
    return plan, result.outputs


def srgb_codes(outputs: dict) -> np.ndarray:
    """The colour output as 8-bit sRGB codes (int)."""
    from rgraph.passes.tonemap_ref import srgb_codes as codes

    return codes(outputs["color"][..., :3])


def stats(outputs: dict) -> dict[str, int]:
    from rgraph.passes.cluster_report import stats_of

    return stats_of(outputs["cluster_stats"])
