"""Second round of outside-user inputs for ray tracing (FORMAT.md 5 and 7; tests/fixtures/unseen).
Each test pins a bug these inputs found:

- vectors the scene validator accepts (finite, nonzero) but whose squared length under- or
  overflows float64 (a look_at 1e-200 m ahead, an up or a light direction of length 1e-200 or
  1e300): the camera basis raised ``ValueError: cannot normalize`` (a traceback from ``rgraph
  run``), a light direction of 1e300 became the zero vector (NaN pixels in the ray tracing
  graphs, a traceback in the raster ones) and one of 1e-200 silently became (0, -1, 0);
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT, TESTS
from rt_helpers import run_rt

from rgraph.cli import main

FIXTURES = TESTS / "fixtures" / "unseen"
GRAPHS = ROOT / "graphs"
vulkan = pytest.mark.vulkan


def _s(name: str) -> str:
    return str(FIXTURES / "scenes" / f"{name}.yaml")


# ------------------------------------------------------------------ device-free
def test_extreme_vectors_normalize_to_their_own_direction() -> None:
    from rgraph.scene.build import load_scene_data
    from rgraph.scene.camera import orthonormal_basis

    data = load_scene_data(_s("extreme_vectors"), (8, 6))
    h = np.sqrt(0.5)
    assert np.allclose(data.lights[0].direction, [h, -h, 0])  # not the (0, -1, 0) fallback
    assert np.allclose(data.lights[1].direction, [0, -h, -h])  # not the zero vector
    cam = data.model.camera
    right, up, fwd = orthonormal_basis(np.subtract(cam.look_at, cam.position), cam.up)
    assert np.allclose(np.stack([right, up, fwd]), [[1, 0, 0], [0, 1, 0], [0, 0, -1]])


# ------------------------------------------------------------------ on the device
@vulkan
def test_extreme_vectors_render_finite_and_the_hybrid_equals_the_stand_alone() -> None:
    _, alone = run_rt(GRAPHS / "rt_standalone.yaml", _s("extreme_vectors"), (8, 6))
    _, hybrid = run_rt(GRAPHS / "rt_hybrid.yaml", _s("extreme_vectors"), (8, 6))
    color = np.asarray(alone["color"])
    assert np.isfinite(color).all() and np.isfinite(np.asarray(hybrid["color"])).all()
    assert color[..., :3].std() > 0.01  # the box, the mirror and the sky: not one flat colour
    assert np.abs(color - np.asarray(hybrid["color"])).max() < 0.02


@vulkan
def test_extreme_vectors_run_the_raster_path_under_validation(capsys) -> None:
    capsys.readouterr()
    rc = main(["run", "clustered", "--scene", _s("extreme_vectors"), "--size", "8x6", "--validate"])
    err = capsys.readouterr().err
    assert "Traceback" not in err and rc == 0, err
    assert "0 validation message(s)" in err
