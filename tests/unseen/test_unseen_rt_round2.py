"""Second round of outside-user inputs for ray tracing (FORMAT.md 5 and 7; tests/fixtures/unseen).
Each test pins a bug these inputs found:

- vectors the scene validator accepts (finite, nonzero) but whose squared length under- or
  overflows float64 (a look_at 1e-200 m ahead, an up or a light direction of length 1e-200 or
  1e300): the camera basis raised ``ValueError: cannot normalize`` (a traceback from ``rgraph
  run``), a light direction of 1e300 became the zero vector (NaN pixels in the ray tracing
  graphs, a traceback in the raster ones) and one of 1e-200 silently became (0, -1, 0);
- coordinates and light radiance past float32 (a camera or mesh 1e300 m out, a scale or an
  instance spacing of 1e300, a light of 3e38 or colour 1e300): tracebacks (``struct.pack``
  OverflowError in the ray tracing tables, the camera basis) or inf pixels; the scene now
  limits coordinates to 1e18 m (a mesh's reach included) and radiance to 1e30, located;
- an accel that only culled passes touch was never sized: the plan's ``culled`` entries reported
  it as 1 byte (the saved memory understated); now its real size, and never an error.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT, TESTS
from rt_helpers import run_rt
from test_unseen_inputs import _diagnostics, _s  # the first round's fixture helpers

from rgraph.cli import main

FIXTURES = TESTS / "fixtures" / "unseen"
GRAPHS = ROOT / "graphs"
vulkan = pytest.mark.vulkan


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


BAD_SCENES = {  # tests/fixtures/unseen/bad_scenes: (line, col, message start) each
    "far_camera": [(3, 24, "'position': Input should be less than or equal to 1000000000000000000")],
    "far_mesh": [(6, 77, "'position': Input should be less than or equal to 1000000000000000000")],
    "huge_mesh": [(8, 5, "mesh 1 (box) reaches past 1e+18 m from the origin")],
    "huge_radiance": [(5, 5, "radiance (color x intensity) 3e+38 is above 1e+30"),
                      (6, 5, "radiance (color x intensity) 1e+300 is above 1e+30"),
                      (7, 80, "'intensity': Input should be less than or equal to 1000000000000000000000000000000")],
}


def test_every_bad_scene_is_listed() -> None:
    assert sorted(p.stem for p in (FIXTURES / "bad_scenes").glob("*.yaml")) == sorted(BAD_SCENES)


@pytest.mark.parametrize("name", sorted(BAD_SCENES))
def test_scenes_past_the_float32_limits_are_located(name: str, capsys) -> None:
    scene = str(FIXTURES / "bad_scenes" / f"{name}.yaml")
    for command in ("validate", "compile"):
        rc, diags = _diagnostics(capsys, [command, str(GRAPHS / "rt_hybrid.yaml"), "--scene", scene])
        assert rc == 2, command
        assert [(d["file"], d["line"], d["col"]) for d in diags] == [(scene, ln, col) for ln, col, _ in BAD_SCENES[name]]
        for d, (_, _, start) in zip(diags, BAD_SCENES[name], strict=True):
            assert d["message"].startswith(start), d["message"]


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


@vulkan
def test_a_scene_at_the_limits_renders_finite(capsys) -> None:
    _, out = run_rt(GRAPHS / "rt_hybrid.yaml", _s("at_the_limits"), (8, 5))
    color = np.asarray(out["color"])
    assert np.isfinite(color).all() and color.max() == 65504.0  # saturated, not inf
    capsys.readouterr()
    rc = main(["run", "clustered", "--scene", _s("at_the_limits"), "--size", "8x5", "--validate"])
    err = capsys.readouterr().err
    assert rc == 0 and "0 validation message(s)" in err, err


@pytest.mark.parametrize("scene", ["opaque_only", "no_meshes"])
def test_a_culled_accel_reports_the_bytes_it_would_have_taken(scene, tmp_path):
    """rt_culled_opaque culls the build and the trace of ``tlas`` on an opaque scene: their
    ``culled`` entries report the accel at the size it has when kept (probe geometry), with the
    scene's meshes or without any (sizing a culled accel never raises)."""
    from rgraph.compiler.pipeline import compile_graph

    graph = FIXTURES / "graphs" / "rt_culled_opaque.yaml"
    kept = compile_graph(str(graph), scene_path=GRAPHS / "scenes" / "rt_tiny.yaml", size=(16, 16))
    tlas = next(r["bytes"] for r in kept["resources"] if r["name"] == "tlas")
    assert tlas > 64 and not kept["culled"]
    plan = compile_graph(str(graph), scene_path=_s(scene), size=(16, 16))
    culled = {c["pass"]: c for c in plan["culled"]}
    assert set(culled) == {"build", "reflect"} and "tlas" not in {r["name"] for r in plan["resources"]}
    assert culled["build"]["resources"] == ["tlas"] and culled["build"]["bytes"] == tlas
    refl = next(c for c in plan["culled"] if c["pass"] == "reflect")
    assert refl["bytes"] > tlas  # refl (an image) and tlas
