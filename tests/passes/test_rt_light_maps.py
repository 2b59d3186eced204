"""The hybrid's light maps (passes/raytrace_lightmap.py, shaders/rt/light_maps.glsl) on lavapipe:
the maps hold the distances a NumPy float64 ray caster finds from each light, the hybrid's
image with them agrees with the stand-alone's (which traces every shadow ray), the shading
passes really consult them (maps of a moved light change the shadows), and scenes the maps
cannot serve (deformable meshes, ``rt.light_maps: 0``) trace every shadow ray."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT
from rt_helpers import run_rt

from rgraph.resources import builtin_passes

builtin_passes()
from rgraph.passes import raytrace_lightmap  # noqa: E402
from rgraph.passes.rt_model import build_tables  # noqa: E402
from rgraph.passes.rt_ref import intersect  # noqa: E402

TIR = ROOT / "tests" / "data" / "rt" / "wave_tir.yaml"  # a directional and a point light
TINY = ROOT / "graphs" / "scenes" / "rt_tiny.yaml"
FAR = 3.0e38


def _run(graph: str, scene, size: int, params=None, extra=()):
    return run_rt(graph, scene, (size, size), params, extra, frames=2)


def _image(outputs) -> np.ndarray:
    return outputs["color"][..., :3].astype(np.float64)


def psnr(a, b) -> float:
    mse = float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(1.0 / mse)


def face_direction(face: int, a: float, b: float) -> np.ndarray:
    """light_maps.glsl: face_direction."""
    s = 1.0 if face % 2 == 0 else -1.0
    return np.array([(s, a, b), (a, s, b), (a, b, s)][face // 2], dtype=np.float64)


def reference_ray(data, li: int, face: int, x: int, y: int, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray] | None:
    """Origin and direction of texel (x, y) of light ``li``'s layer ``face`` (light_map.rgen)."""
    info = np.frombuffer(raytrace_lightmap.light_map_info(data, size, len(data.lights)), dtype=np.float32)
    m = info[64 * li:64 * li + 64].astype(np.float64).reshape(16, 4)
    if m[0, 3] > 0.5:
        a, b = 2.0 * (np.array([x, y]) + 0.5) / np.array(size) - 1.0
        d = face_direction(face, a, b)
        return m[0, :3], d / np.linalg.norm(d)
    if face >= m[3, 3]:
        return None
    grid, dv = m[4 + 2 * face], m[5 + 2 * face, 3]
    return grid[:3] + (x + 0.5) * grid[3] * m[1, :3] + (y + 0.5) * dv * m[2, :3], m[3, :3]


@pytest.mark.vulkan
def test_light_maps_hold_the_distances_of_a_float64_ray_caster():
    from rgraph.scene.build import load_scene_data

    plan, out = _run("rt_hybrid", TIR, 24, extra=("light_maps",))
    maps = out["light_maps"][..., 0].astype(np.float64)
    data = load_scene_data(TIR, (24, 24))
    tables = build_tables(data)
    size = (maps.shape[2], maps.shape[1])
    assert maps.shape == (12, size[1], size[0])  # two lights, 6 layers each
    checked = agree = 0
    for li in range(len(data.lights)):
        for face in range(6):
            for y in range(0, size[1], 3):
                for x in range(0, size[0], 3):
                    ray = reference_ray(data, li, face, x, y, size)
                    if ray is None:
                        continue
                    hit = intersect(tables, *ray)
                    want = FAR if hit is None else hit[0]
                    got = maps[6 * li + face, y, x]
                    checked += 1
                    agree += bool(np.isclose(got, want, rtol=1e-4, atol=1e-5))
    assert checked > 500
    assert agree >= 0.99 * checked  # a ray through a shared edge may find either triangle first


@pytest.mark.vulkan
@pytest.mark.parametrize("scene", [TIR, TINY], ids=["wave_tir", "rt_tiny"])
def test_hybrid_with_light_maps_agrees_with_tracing_every_shadow_ray(scene):
    _plan, alone = _run("rt_standalone", scene, 32)
    _plan, mapped = _run("rt_hybrid", scene, 32)
    _plan, traced = _run("rt_hybrid", scene, 32, params={"rt.light_maps": "0"})
    a, b, c = _image(alone), _image(mapped), _image(traced)
    assert np.isfinite(b).all()
    assert psnr(a, b) >= 45
    assert (np.abs(b - c).max(axis=2) > 1e-3).sum() <= 2  # sub-texel occluders may flip a pixel


@pytest.mark.vulkan
def test_shading_passes_consult_the_maps(monkeypatch):
    """Maps traced from a moved point light (and read as that light's) put the shadows in the
    wrong places: the shadow rays' outcome comes from the maps."""
    original = raytrace_lightmap.light_map_info

    def moved(data, size, mapped):
        info = np.frombuffer(original(data, size, mapped), dtype=np.float32).copy()
        for li in range(mapped):
            if info[64 * li + 3] > 0.5:
                info[64 * li:64 * li + 3] += np.float32(3.0)
        return info.tobytes()

    _plan, honest = _run("rt_hybrid", TIR, 32)
    monkeypatch.setattr(raytrace_lightmap, "light_map_info", moved)
    _plan, wrong = _run("rt_hybrid", TIR, 32)
    assert (np.abs(_image(honest) - _image(wrong)).max(axis=2) > 1e-2).sum() >= 20


def test_lights_are_mapped_only_where_the_maps_stay_valid():
    """No map over deformable meshes, with rt.light_maps 0, past four lights or the layers."""

    class Setup:
        def __init__(self, layers, light_maps=1, deformed=None):
            self.layers, self.light_maps = layers, light_maps
            self.accels = type("A", (), {"deformed": deformed})()

        def has(self, name):
            return name == "light_maps"

        def param(self, name, default=None):
            return self.light_maps if name == "rt.light_maps" else default

        def resource_plan(self, name):
            return {"layers": self.layers}

    lights = type("D", (), {"lights": [object()] * 6})()
    assert raytrace_lightmap.mapped_lights(Setup(24), lights) == 4
    assert raytrace_lightmap.mapped_lights(Setup(12), lights) == 2
    assert raytrace_lightmap.mapped_lights(Setup(24, light_maps=0), lights) == 0
    assert raytrace_lightmap.mapped_lights(Setup(24, deformed=object()), lights) == 0
    assert raytrace_lightmap.mapped_lights(Setup(1), lights) == 0


def test_directional_cascades_lie_outside_the_scene_and_cover_the_view():
    from rgraph.passes.raytrace_lightmap import View, cascade_depths, slice_corners

    lo, hi = np.array([-1.0, -2.0, 0.5]), np.array([3.0, 1.0, 6.0])
    to_light = np.array([0.3, 0.9, -0.2])
    view = View(np.eye(3), 0.5, 1.5, 0.1)  # looking along +z from the origin
    rows = np.array(raytrace_lightmap.directional_frame(to_light, lo, hi, (40, 30), view)).reshape(16, 4)
    u, v, w, cascades = rows[1, :3], rows[2, :3], rows[3, :3], int(rows[3, 3])
    assert np.allclose(w, -to_light / np.linalg.norm(to_light)) and cascades == raytrace_lightmap.CASCADES
    depths = cascade_depths(view, lo, hi)
    assert depths[0] == 0.1 and np.isclose(depths[-1], 6.0) and np.all(np.diff(np.log(depths)) > 0)
    box = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    sizes = []
    for k in range(cascades):
        c0, du, dv = rows[4 + 2 * k, :3], rows[4 + 2 * k, 3], rows[5 + 2 * k, 3]
        assert ((box - c0) @ w > 0).all()  # the grid's plane lies outside the scene's box
        inside = slice_corners(view, depths[k], depths[k + 1])
        inside = inside[np.all((inside >= lo) & (inside <= hi), axis=1)]  # the slice's corners in the box
        i, j = (inside - c0) @ u / du, (inside - c0) @ v / dv
        assert (i >= 2 - 1e-9).all() and (i <= 38 + 1e-9).all() and (j >= 2 - 1e-9).all() and (j <= 28 + 1e-9).all()
        sizes.append(max(du, dv))
    assert sizes == sorted(sizes)  # finest first
    whole = np.array(raytrace_lightmap.directional_frame(to_light, lo, hi, (40, 30))).reshape(16, 4)
    assert int(whole[3, 3]) == 1  # without a view: one grid over the whole box


@pytest.mark.parametrize("param", ["rt.light_map_guard=-1", "rt.light_map_guard=nan", "rt.light_maps=3",
                                   "rt.max_depth=0"])
def test_bad_ray_tracing_params_are_refused_before_the_device_opens(capsys, param):
    from rgraph.cli import main

    assert main(["run", "rt_hybrid", "--scene", str(TINY), "--size", "8x8", "-p", param]) == 2
    err = capsys.readouterr().err
    assert err.startswith("<command line>:1:1: error: param ") and "Traceback" not in err and "device 0" not in err
