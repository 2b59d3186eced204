"""Scenes a user may write that the bundled ones never exercise, run on the device at tiny
sizes (benchmarks/sweep_combinations.py finds these): zero-size and zero-scale meshes (were a
LinAlgError traceback), and a ray tracing graph's ``--out`` PNG (was all zero)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from rgraph.cli import main

DEGENERATE = """scene: 1
camera: {position: [0, 0.8, 2.5], look_at: [0, 0.2, 0]}
lights: [{type: directional, direction: [-0.3, -1, -0.2], shadows: true}, {type: point, position: [0.5, 1, 0.8]}]
materials: {m: {}}
meshes:
  - {shape: plane, params: {size: [4, 4]}, material: m}
  - {shape: box, material: m, scale: 0}
  - {shape: box, material: m, scale: [1, 1, 0], position: [0, 0.5, 0]}
  - {shape: sphere, params: {radius: 0}, material: m}
"""


@pytest.fixture()
def degenerate(tmp_path: Path) -> Path:
    path = tmp_path / "degenerate.yaml"
    path.write_text(DEGENERATE)
    return path


@pytest.mark.parametrize("graph", ["clustered", "surgery"])
def test_degenerate_meshes_raster(graph: str, degenerate: Path) -> None:
    assert main(["run", graph, "--scene", str(degenerate), "--size", "7x3", "--frames", "2", "--validate"]) == 0


def test_degenerate_meshes_ray_traced(degenerate: Path, tmp_path: Path) -> None:
    out = tmp_path / "rt.png"
    assert main(["run", "rt_standalone", "--scene", str(degenerate), "--size", "16x9", "--frames", "1",
                 "--check-data", "--out", str(out)]) == 0
    rgba = matplotlib.image.imread(out)
    assert rgba.shape == (9, 16, 4) and (rgba[..., 3] == 1.0).all()
    assert np.isfinite(rgba).all() and rgba[..., :3].max() > 0.2  # sky and a lit floor, not all zero


MANY_LIGHTS = """scene: 1
camera: {position: [0, 0.8, 2.5], look_at: [0, 0.2, 0]}
lights: [{generate: point, count: 1100, seed: 1, bounds: [[-2, 0.1, -2], [2, 1.5, 2]]}]
materials: {m: {}}
meshes: [{shape: plane, params: {size: [4, 4]}, material: m}]
"""


def test_more_lights_than_a_uniform_buffer_binds(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """surgery's forward pass reads ``lights`` as a uniform buffer: 1,100 lights (70,400 bytes)
    were bound past maxUniformBufferRange (65,536 on lavapipe: a validation error)."""
    path = tmp_path / "lights.yaml"
    path.write_text(MANY_LIGHTS)
    assert main(["run", "surgery", "--scene", str(path), "--size", "7x3", "--frames", "2", "--validate"]) == 0
    err = capsys.readouterr().err
    assert "1,024 of 1,100 lights are shaded" in err and "0 validation message(s)" in err


def test_raster_run_locates_a_shape_it_cannot_build(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Was ``<device>:1:1: scene ...: mesh 0 ...``: the scene is built when the device runs."""
    path = tmp_path / "bad.yaml"
    path.write_text("scene: 1\nmaterials: {m: {}}\nmeshes:\n  - {shape: segments, params: {turns: 4}, material: m}\n")
    assert main(["run", "clustered", "--scene", str(path), "--size", "7x3", "--json"]) == 2
    import json

    diags = json.loads(capsys.readouterr().out)["diagnostics"]
    assert [(d["file"], d["line"], d["col"]) for d in diags] == [(str(path), 4, 5)]
    assert "unknown parameter(s) turns" in diags[0]["message"]
