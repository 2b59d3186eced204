"""FORMAT.md 7 light generators: seeded, inside their bounds and ranges, counted as features;
spot cones and radius 0 accepted, bad ranges rejected with one located line."""

from __future__ import annotations

import numpy as np
import pytest

from rgraph.errors import RGraphError
from rgraph.scene import packing
from rgraph.scene.build import load_scene_data
from rgraph.spec.scene import load_scene

GEN = ("  - {generate: point, count: 500, seed: 3, bounds: [[-1, 0, -2], [1, 0.5, 2]], radius: [0.2, 0.7],"
       " intensity: [1, 4]}\n")


def write(tmp_path, lights: str):
    p = tmp_path / "s.yaml"
    p.write_text("scene: 1\nlights:\n  - {type: directional, direction: [0, -1, 0]}\n" + lights)
    return p


def test_generator_is_seeded_bounded_and_counted(tmp_path):
    path = write(tmp_path, GEN + "  - {type: spot, position: [0, 1, 0], direction: [0, -1, 0], cone: [10, 20], radius: 0}\n")
    scene = load_scene(path)
    assert scene.features["lights"] == 502 and scene.features["point_lights"] == 501
    data = load_scene_data(path)
    again = load_scene_data(path)
    pts = np.array([li.position for li in data.lights[1:501]])
    assert np.array_equal(pts, np.array([li.position for li in again.lights[1:501]]))
    assert np.all(pts >= [-1, 0, -2]) and np.all(pts <= [1, 0.5, 2]) and len(np.unique(pts[:, 0])) == 500
    radii = np.array([li.radius for li in data.lights[1:501]])
    inten = np.array([li.intensity for li in data.lights[1:501]])
    assert radii.min() >= 0.2 and radii.max() <= 0.7 and radii.std() > 0.1
    assert inten.min() >= 1 and inten.max() <= 4
    spot = data.lights[-1]
    assert spot.radius == 0 and np.isclose(spot.cos_inner, np.cos(np.radians(10)))
    raw = np.frombuffer(packing.scene_lights_bytes(data), np.float32).reshape(-1, 16)
    assert np.isclose(raw[-1, 11], np.cos(np.radians(10))) and np.isclose(raw[-1, 15], np.cos(np.radians(20)))
    assert raw[1, 11] == -1 and np.isclose(raw[1, 15], data.lights[1].intensity)  # point: shadow layer, intensity
    other = load_scene_data(write(tmp_path, GEN.replace("seed: 3", "seed: 4")))
    assert not np.array_equal(pts, np.array([li.position for li in other.lights[1:501]]))


@pytest.mark.parametrize("item,message", [
    ("{generate: point, count: 4, bounds: [[0, 0, 0], [1, 1, 1]], radius: [2, 1]}", "radius must be"),
    ("{generate: point, count: 4, bounds: [[1, 0, 0], [0, 1, 1]]}", "bounds must be"),
    ("{generate: point, count: -1, bounds: [[0, 0, 0], [1, 1, 1]]}", "count"),
    ("{generate: spot, count: 4, bounds: [[0, 0, 0], [1, 1, 1]]}", "generate"),
    ("{type: spot, cone: [50, 40]}", "cone must be"),
    ("{generate: point, cont: 4, bounds: [[0, 0, 0], [1, 1, 1]]}", "unknown key 'cont'"),
    ("{type: point, radiuss: 4}", "did you mean 'radius'"),
])
def test_bad_generators_are_located_errors(tmp_path, item, message):
    path = write(tmp_path, f"  - {item}\n")
    with pytest.raises(RGraphError) as err:
        load_scene(path)
    assert f"{path}:4:" in str(err.value) and message in str(err.value)


def test_bundled_lighting_scenes():
    from locations import ROOT

    scenes = ROOT / "graphs" / "scenes"
    test, many = load_scene_data(scenes / "lighting_test.yaml"), load_scene_data(scenes / "many_lights.yaml")
    assert len(test.lights) == 25 and len(many.lights) == 4096
    for data in (test, many):
        boxes = next(m for m in data.meshes if m.name.endswith(":box"))
        assert boxes.instances == 968 and data.draw_count == 969  # one instanced draw of 968 boxes + the floor
        assert all(li.type == 1 and li.radius > 0 for li in data.lights)
