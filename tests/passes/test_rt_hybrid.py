"""graphs/rt_hybrid.yaml on lavapipe: the hybrid image agrees with the stand-alone one (same
lighting model and materials; the study reports 37.5-61.4 dB, the target is >= 45 dB), the
compacted ray list holds exactly the pixels whose material reflects or refracts, and a scene
without such materials culls the secondary-ray passes."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT
from rt_helpers import run_rt

from rgraph.compiler.pipeline import compile_graph
from rgraph.resources import builtin_passes

builtin_passes()
from rgraph.passes.raytrace_hybrid import (  # noqa: E402,E501
    decode_visibility,
    instance_materials,
    needs_secondary_rays,
    prim_bits,
)

SCENE = ROOT / "graphs" / "scenes" / "rt_tiny.yaml"


def _run(graph: str, size: int, scene=SCENE, extra=(), params=None):
    return run_rt(graph, scene, (size, size), params, extra)


def psnr(a, b) -> float:
    mse = float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(1.0 / mse)


@pytest.mark.vulkan
@pytest.mark.parametrize("graph, wave", [("rt_hybrid", "1"), ("rt_hybrid", "0"), ("rt_hybrid_raster", None)])
def test_hybrid_agrees_with_stand_alone_and_traces_only_the_classified_pixels(graph, wave):
    """Compute visibility buffer (the tree by levels or, the default, in-thread) / hardware raster."""
    params = {} if wave is None else {"rt.wavefront": wave}
    _plan, hybrid = _run(graph, 20, extra=("ray_args", "visibility"), params=params)
    _plan, alone = _run("rt_standalone", 20)
    a, b = alone["color"][..., :3].astype(np.float64), hybrid["color"][..., :3].astype(np.float64)
    assert np.isfinite(b).all()
    assert psnr(a, b) >= 45
    from rgraph.scene.build import load_scene_data

    data = load_scene_data(SCENE, (20, 20))
    mask = needs_secondary_rays(data.materials)[instance_materials(data)]
    ids = hybrid["visibility"][..., 0]
    instance, _prim = decode_visibility(ids, prim_bits(data))
    assert (instance < len(mask)).all()
    expected = int(mask[instance[instance >= 0]].sum())
    args = np.frombuffer(hybrid["ray_args"].tobytes()[:16], dtype=np.uint32)
    # the wavefront's pixel list: (resolve groups, 1, 1, count); the raster variant's: (count, 1, 1);
    # in-thread (rt.wavefront 0) the shade pass walks the trees and lists nothing
    traced = int(args[3] if graph == "rt_hybrid" else args[0])
    if wave == "0":
        assert traced == 0 and 0 < expected < ids.size
    else:
        assert 0 < traced == expected < ids.size


def test_no_reflective_or_refractive_materials_culls_the_secondary_rays(tmp_path):
    scene = tmp_path / "matte.yaml"
    scene.write_text(SCENE.read_text().replace("reflective: 0.85", "reflective: 0.0")
                     .replace("refractive: 0.9, ", ""))
    plan = compile_graph("rt_hybrid", scene_path=scene, size=(16, 16))
    culled = {c["pass"]: c["reason"] for c in plan["culled"]}
    assert set(culled) == {"wave_1", "wave_2", "wave_3", "resolve"}
    assert all(reason == "scene has none of reflective_materials, refractive_materials" for reason in culled.values())
    assert {p["name"] for p in plan["passes"]} == {"build_as", "sky", "light_maps", "vis_clear", "vis_depth", "vis_depth_tiles",
                                                   "vis_id", "vis_id_tiles", "shade"}
    sizes = {r["name"]: r["bytes"] for r in plan["resources"]}
    assert sizes["wave_color"] == 24 and sizes["rays_1"] == 48  # the wavefront's buffers shrink to one entry
    full = compile_graph("rt_hybrid", scene_path=SCENE, size=(16, 16))
    assert not full["culled"]
    raster = compile_graph("rt_hybrid_raster", scene_path=scene, size=(16, 16))
    assert {c["pass"] for c in raster["culled"]} == {"reset_rays", "classify", "secondary"}


# A grazing view: the camera and a point light inside a thin box (the old rt_gallery camera 4),
# inner faces seen edge-on, a light 5 cm from them. Guards the visibility-buffer reconstruction
# (hit point, normals, ray offsets) there; the depth-based G-buffer also passed it on lavapipe.
GRAZING = """scene: 1
name: rt_grazing
camera: {position: [0.0, 3.4, 0.5], look_at: [0.0, 0.0, -0.5], fov_y: 70}
lights:
  - {type: point, position: [0.0, 3.0, 0.0], color: [1.0, 0.95, 0.9], intensity: 0.02}
  - {type: directional, direction: [-0.2, -1.0, -0.3], color: [1.0, 0.98, 0.95], intensity: 1.2}
materials:
  wall: {base_color: [0.9, 0.88, 0.85], roughness: 0.9}
  mirror: {base_color: [0.95, 0.95, 0.95], roughness: 0.0, reflective: 0.95}
meshes:
  - {shape: box, params: {size: [0.1, 4.0, 10.0]}, material: wall, position: [0.0, 2.0, 0.0]}
  - {shape: sphere, params: {radius: 0.02, segments: 8, rings: 4}, material: mirror, position: [0.0, 1.0, 0.0]}
"""


@pytest.mark.vulkan
def test_hybrid_agrees_on_the_visibility_buffer_hard_cases():
    """Camera 1e6 m from the origin, a box through the camera plane, huge, degenerate and
    sub-pixel triangles (tests/data/rt/vis_hard.yaml)."""
    from locations import TESTS

    scene = TESTS / "data" / "rt" / "vis_hard.yaml"
    _plan, hybrid = _run("rt_hybrid", 32, scene=scene)
    _plan, alone = _run("rt_standalone", 32, scene=scene)
    assert psnr(alone["color"][..., :3].astype(np.float64), hybrid["color"][..., :3].astype(np.float64)) >= 45


@pytest.mark.vulkan
@pytest.mark.parametrize("size", [48, 80])
def test_hybrid_agrees_at_grazing_angles_inside_a_thin_box(tmp_path, size):
    scene = tmp_path / "grazing.yaml"
    scene.write_text(GRAZING)
    _plan, hybrid = _run("rt_hybrid", size, scene=scene)
    _plan, alone = _run("rt_standalone", size, scene=scene)
    a, b = alone["color"][..., :3].astype(np.float64), hybrid["color"][..., :3].astype(np.float64)
    assert psnr(a, b) >= 45


def test_visibility_ids_round_trip_and_oversized_scenes_are_refused():
    from types import SimpleNamespace as NS

    def scene(tris, instances):
        return NS(meshes=[NS(data=NS(triangle_count=t), positions=[0] * n, material=k)
                          for k, (t, n) in enumerate(zip(tris, instances, strict=True))])

    data = scene([12, 131072], [2, 3])
    bits = prim_bits(data)
    assert bits == 17 and list(instance_materials(data)) == [0, 0, 1, 1, 1]
    ids = np.array([0, ((4 << bits) | 131071) + 1, 1], dtype=np.uint32)
    inst, prim = decode_visibility(ids, bits)
    assert inst.tolist() == [-1, 4, 0] and prim.tolist() == [-1, 131071, 0]
    with pytest.raises(ValueError, match="32-bit visibility id"):
        prim_bits(scene([1 << 20], [1 << 12]))


@pytest.mark.vulkan
@pytest.mark.parametrize("scene", [SCENE, ROOT / "tests" / "data" / "rt" / "wave_tir.yaml"])
def test_lean_variant_renders_the_bundled_hybrid_image(scene):
    """benchmarks/graphs/rt_hybrid_lean.yaml (no wavefront passes) shades with the same in-thread
    walk as the bundled graph at ``rt.wavefront: 0``: the same image, bit for bit, with none of the
    passes that run empty there."""
    lean_graph = str(ROOT / "benchmarks" / "graphs" / "rt_hybrid_lean.yaml")
    lean_plan, lean = _run(lean_graph, 24, scene=scene)
    _plan, bundled = _run("rt_hybrid", 24, scene=scene)
    assert np.isfinite(lean["color"]).all()
    assert np.array_equal(lean["color"], bundled["color"])
    names = {p["name"] for p in lean_plan["passes"]}
    assert not names & {"wave_1", "wave_2", "wave_3", "resolve"} and "shade" in names
