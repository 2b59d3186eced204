"""Scene camera presets (FORMAT.md 7): ``cameras`` lists presets, ``--camera N`` picks one
(0 = ``camera`` without a list); the plan records a non-default choice; bad indices are one-line
errors; the bundled ray tracing scenes have five cameras and their study's triangle counts
within a factor of two."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from locations import ROOT

from rgraph.compiler.pipeline import compile_graph
from rgraph.errors import RGraphError
from rgraph.scene.build import load_scene_data

SCENES = ROOT / "graphs" / "scenes"


def test_presets_pick_the_camera():
    path = SCENES / "rt_living_room.yaml"
    first, second = load_scene_data(path, camera=0), load_scene_data(path, camera=1)
    assert not np.allclose(first.camera().position, second.camera().position)
    assert np.allclose(second.camera().position, second.model.cameras[1].position)
    plain = load_scene_data(SCENES / "rt_tiny.yaml")
    assert np.allclose(plain.camera().position, plain.model.camera.position)
    with pytest.raises(ValueError, match="no 'cameras' list"):
        load_scene_data(SCENES / "rt_tiny.yaml", camera=1)


def test_an_empty_cameras_list_is_named_as_such(tmp_path):
    """``cameras: []`` is allowed (camera 0 is ``camera``); --camera 1 said it had no list."""
    scene = tmp_path / "empty.yaml"
    scene.write_text((SCENES / "rt_tiny.yaml").read_text() + "\ncameras: []\n")
    with pytest.raises(ValueError, match="an empty 'cameras' list"):
        load_scene_data(scene, camera=1)


def test_plan_records_the_camera_and_rejects_bad_indices():
    plan = compile_graph("rt_standalone", scene_path=SCENES / "rt_gallery.yaml", size=(16, 16), camera=3)
    assert plan["camera"] == 3
    assert "camera" not in compile_graph("rt_standalone", size=(16, 16))
    with pytest.raises(RGraphError, match="out of range"):
        compile_graph("rt_standalone", scene_path=SCENES / "rt_gallery.yaml", size=(16, 16), camera=5)
    out = subprocess.run([sys.executable, "-m", "rgraph", "compile", "rt_standalone", "--camera", "2",
                          "--size", "16x16"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "--camera" in out.stderr


@pytest.mark.parametrize("name,faces", [("rt_living_room", 0.6e6), ("rt_conference", 1.1e6), ("rt_gallery", 1.0e6)])
def test_bundled_scenes(name, faces):
    from rgraph.spec.scene import load_scene

    scene = load_scene(SCENES / f"{name}.yaml")
    assert len(scene.model.cameras) == 5
    assert scene.features["reflective_materials"] and scene.features["refractive_materials"]
    data = load_scene_data(SCENES / f"{name}.yaml")
    total = sum(m.data.triangle_count * m.instances for m in data.meshes)
    assert faces / 2 <= total <= faces * 2
