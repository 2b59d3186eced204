"""Scene items the builder cannot make are located refusals (``FILE:LINE:COL``), not a
ValueError (a traceback from ray tracing graphs, ``<device>:1:1`` from raster ones); a
singular mesh transform (a zero scale) has a normal matrix."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rgraph.errors import RGraphError
from rgraph.scene.build import load_scene_data
from rgraph.scene.camera import inverse_transpose3, model_matrix, normal_matrix

HEAD = "scene: 1\nmaterials: {m: {}}\n"


def _scene(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(HEAD + text)
    return path


def _refusal(path: Path) -> str:
    with pytest.raises(RGraphError) as info:
        load_scene_data(path)
    return str(info.value.diagnostics[0])


def test_unknown_shape_param_is_located_at_the_mesh(tmp_path: Path) -> None:
    path = _scene(tmp_path, "meshes:\n  - {shape: box, material: m}\n  - {shape: segments, params: {turns: 4}, material: m}\n")
    text = _refusal(path)
    assert text.startswith(f"{path}:5:5: error: mesh 1 (segments): shape 'segments': unknown parameter(s) turns")


def test_fifth_shadow_light_is_located(tmp_path: Path) -> None:
    lights = "".join("  - {type: directional, direction: [0, -1, 0], shadows: true}\n" for _ in range(6))
    path = _scene(tmp_path, "lights:\n  - {type: point, position: [0, 1, 0]}\n" + lights)
    text = _refusal(path)
    assert text.startswith(f"{path}:9:5: error: at most 4 shadow-casting lights are supported")
    assert "5 of 6" in text


def test_four_shadow_lights_build(tmp_path: Path) -> None:
    lights = "".join("  - {type: directional, direction: [0, -1, 0], shadows: true}\n" for _ in range(4))
    data = load_scene_data(_scene(tmp_path, "lights:\n" + lights))
    assert [li.shadow_layer for li in data.lights] == [0, 1, 2, 3]


def test_inverse_transpose_unchanged_when_invertible() -> None:
    m = model_matrix((1.0, 2.0, 3.0), (10.0, 20.0, 30.0), (0.5, 2.0, 3.0))
    assert np.array_equal(inverse_transpose3(m), np.linalg.inv(m[:3, :3]).T)


@pytest.mark.parametrize("scale", [0.0, (1.0, 1.0, 0.0), (0.0, 0.0, 2.0)])
def test_singular_scale_has_a_finite_normal_matrix(scale) -> None:
    nm = normal_matrix(model_matrix((0.0, 0.0, 0.0), (0.0, 30.0, 0.0), scale))
    assert np.isfinite(nm).all()


def test_flattened_mesh_keeps_its_plane_normal() -> None:
    nm = inverse_transpose3(model_matrix((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (2.0, 3.0, 0.0)))
    n = nm @ np.array([0.0, 0.0, 1.0])
    assert np.allclose(n / np.linalg.norm(n), [0.0, 0.0, 1.0])


def test_ray_tracing_compile_refuses_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Was a traceback: the accel sizes build the scene at compile time."""
    from rgraph.cli import main

    path = _scene(tmp_path, "meshes:\n  - {shape: segments, params: {radius: 1}, material: m}\n")
    assert main(["compile", "rt_standalone", "--scene", str(path), "--size", "8x8", "--profile", "lavapipe"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"{path}:4:5: error: mesh 0 (segments)"), err
