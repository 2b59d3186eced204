"""Clustered forward lighting on lavapipe under validation + synchronization validation.

- froxel bounds and light lists against passes/clustered_ref.py (float64): every list holds
  each light the reference accepts with spheres and froxels shrunk by ASSIGN_MARGIN and none it
  rejects with them grown (tight), in ascending order (points, spots, a directional light);
- the all-lights hdr against the float64 shading of the floor (window, cone, GGX);
- hard cases, each clustered against all_lights within one 8-bit sRGB code after tonemapping:
  0 and 1 lights, 65,536 lights with an overflowing list (reported in cluster_stats), a light
  behind the camera reaching the frustum, radius 0 and 1e4, a light on a froxel corner, the camera
  inside a light, near plane 1e-4, objects at 1e5 m, spot lights (narrow, zero-width and
  hemispherical cones).
"""

from __future__ import annotations

import numpy as np
import pytest
from clustered_helpers import graph_with_outputs, render, scene_file, srgb_codes, stats

from rgraph.resources import builtin_passes

builtin_passes()  # rgraph.passes from a plain checkout too (the GPU machines)
from rgraph.passes import clustered_ref as ref  # noqa: E402

from rgraph.scene.build import load_scene_data  # noqa: E402

SIZE = (64, 48)
MIXED = """  - {type: directional, direction: [-0.3, -1, -0.2], intensity: 0.3}
  - {generate: point, count: 300, seed: 5, bounds: [[-8, 0.2, -8], [8, 3, 8]], radius: [0.3, 2.5], intensity: [0.5, 2]}
  - {type: spot, position: [-2, 3, 2], direction: [0.3, -1, -0.1], cone: [15, 25], radius: 8, intensity: 30}
  - {type: spot, position: [3, 2, 4], direction: [-1, -0.5, -1], cone: [5, 40], radius: 12, intensity: 30}
"""


def _lists(outputs: dict, grid: ref.Grid, kind: str, lights: int) -> list[list[np.ndarray]]:
    """Per slice, per tile (row-major): the light indices of the GPU's list (either encoding)."""
    cells = outputs["light_grid"]  # (slices, gy, gx, 4)
    idx = outputs["light_indices"].view(np.uint32)
    gx, gy = grid.tiles
    words = -(-lights // 32)
    out = []
    for k in range(grid.slices):
        row = []
        for y in range(gy):
            for x in range(gx):
                off, cnt = int(cells[k, y, x, 0]), int(cells[k, y, x, 1])
                if kind == "indices":
                    row.append(idx[off:off + cnt])
                else:
                    bits = np.unpackbits(idx[off:off + words].view(np.uint8), bitorder="little")[:lights]
                    row.append(np.nonzero(bits)[0])
                    assert len(row[-1]) == cnt
        out.append(row)
    return out


@pytest.mark.vulkan
@pytest.mark.parametrize("kind", ["indices", "bitmask"])
def test_froxel_bounds_and_lists_match_the_reference(tmp_path, kind):
    scene = scene_file(tmp_path, MIXED)
    graph = graph_with_outputs(tmp_path, ("froxel_bounds", "light_grid", "light_indices"))
    plan, out = render(scene, size=SIZE, graph=graph, params={"clusters.list": kind, "clusters.tile": "16",
                                                             "clusters.slices": "8"})
    data = load_scene_data(scene, SIZE)
    grid = ref.grid_for(data, 16, 8)
    lo, hi = ref.froxel_bounds(grid)
    plo, phi = ref.padded(grid, lo, hi)
    fb = out["froxel_bounds"].astype(np.float64)  # (2 * slices, gy, gx, 4)
    got_lo = np.moveaxis(fb[0::2, ..., :3], 0, 2)
    got_hi = np.moveaxis(fb[1::2, ..., :3], 0, 2)
    finite = np.abs(phi) < 1e29
    scale = np.maximum(np.abs(plo), np.abs(phi)).max(axis=-1, keepdims=True)
    assert np.all(np.abs(got_lo - plo)[finite] <= 1e-5 * np.broadcast_to(scale, plo.shape)[finite] + 1e-6)
    assert np.all(np.abs(got_hi - phi)[finite] <= 1e-5 * np.broadcast_to(scale, phi.shape)[finite] + 1e-6)
    lights = ref.light_table(data)
    must = ref.touches(lights, lo, hi, -ref.ASSIGN_MARGIN)  # (gy, gx, s, n)
    may = ref.touches(lights, lo, hi, ref.ASSIGN_MARGIN)
    lists = _lists(out, grid, kind, len(data.lights))
    gx, gy = grid.tiles
    total = 0
    for k in range(grid.slices):
        for y in range(gy):
            for x in range(gx):
                got = lists[k][y * gx + x]
                assert np.all(np.diff(got.astype(np.int64)) > 0)  # ascending, no repeats
                have = np.zeros(len(data.lights), bool)
                have[got] = True
                assert not np.any(must[y, x, k] & ~have), f"froxel {(x, y, k)} misses lights"
                assert not np.any(have & ~may[y, x, k]), f"froxel {(x, y, k)} lists lights it cannot reach"
                total += len(got)
    s = stats(out)
    entries = total if kind == "indices" else grid.froxels * -(-len(data.lights) // 32)
    assert s["references"] == entries and s["overflowed_froxels"] == 0 and s["capacity"] == 4194304
    assert must[..., 0].all()  # the directional light is everywhere
    spots = [i for i, li in enumerate(data.lights) if li.type == ref.LIGHT_SPOT]
    sphere_only = ref.touches({**lights, "type": np.where(lights["type"] == ref.LIGHT_SPOT, 1, lights["type"])},
                              lo, hi, ref.ASSIGN_MARGIN)
    assert np.any(sphere_only[..., spots] & ~may[..., spots])  # the cone test culls froxels the sphere meets
    assert total < 0.5 * grid.froxels * len(data.lights)  # the lists are far shorter than every light
    assert max(len(x) for row in lists for x in row) < len(data.lights) // 2  # the unbounded last slice too


@pytest.mark.vulkan
def test_all_lights_hdr_matches_the_float64_shading(tmp_path):
    floor = """materials:
  floor: {base_color: [0.6, 0.5, 0.4], roughness: 0.5, metallic: 0}
meshes:
  - {shape: plane, params: {size: [60, 60], subdivisions: 1}, material: floor}
"""
    lights = """  - {type: point, position: [1, 0.8, 3], radius: 3, intensity: 8, color: [1, 0.8, 0.6]}
  - {type: spot, position: [-2, 2, 2], direction: [0.2, -1, 0], cone: [10, 30], radius: 6, intensity: 40}
  - {type: directional, direction: [0, -1, -1], intensity: 0.2}
"""
    scene = scene_file(tmp_path, lights, meshes=floor)
    graph = graph_with_outputs(tmp_path, ("hdr", "depth"))
    plan, out = render(scene, size=SIZE, graph=graph, mode="all_lights")
    data = load_scene_data(scene, SIZE)
    cam = data.camera(0)
    depth = out["depth"][..., 0].astype(np.float64)
    w, h = SIZE
    px, py = np.meshgrid((np.arange(w) + 0.5) / w, (np.arange(h) + 0.5) / h)
    ndc = np.stack([px * 2 - 1, py * 2 - 1, depth, np.ones_like(depth)], axis=-1)
    floor_px = depth > 0
    ndc[~floor_px, 2] = 1.0  # background: any finite point (masked out below)
    world = ndc @ cam.inv_view_proj.T
    world = world[..., :3] / world[..., 3:4]
    from rgraph.scene.packing import AMBIENT

    want = ref.shade(ref.light_table(data), world, np.broadcast_to([0.0, 1.0, 0.0], world.shape), [0.6, 0.5, 0.4],
                     0.5, 0.0, AMBIENT)
    got = out["hdr"][..., :3].astype(np.float64)
    assert floor_px.mean() > 0.3
    err = np.abs(got - want) - (0.01 * np.abs(want) + 0.002)
    assert err[floor_px].max() <= 0, f"worst excess {err[floor_px].max()}"
    spot_lit = want[..., 2] > 0.1 + want[..., 2].min()
    assert spot_lit[floor_px].mean() > 0.02 and (~spot_lit[floor_px]).mean() > 0.2  # the cone edge is in view


def _boundary_light(tmp_path) -> str:
    """A light exactly on a froxel corner: tile boundaries x = 0 and y = 1/3 in NDC (8-pixel tiles of
    64 x 48), at a slice start."""
    data = load_scene_data(scene_file(tmp_path, "", name="probe"), SIZE)
    cam = data.camera(0)
    grid = ref.grid_for(data, 8, 12)  # clustered_helpers.render's grid
    starts = ref.slice_starts(grid)
    ray = np.array([0.0, (1 / 3) / cam.proj[1, 1], -1.0])  # view-space direction per unit distance
    world_ray = cam.inv_view[:3, :3] @ ray
    hit = -cam.position[1] / world_ray[1]  # distance where the ray meets the floor
    d = starts[starts < hit].max()
    p = cam.position + d * world_ray
    return f"  - {{type: point, position: [{float(p[0])!r}, {float(p[1])!r}, {float(p[2])!r}], radius: 1.5, intensity: 6}}"


FAR_MESHES = """materials:
  box: {base_color: [0.7, 0.7, 0.72], roughness: 0.4, metallic: 0}
meshes:
  - {shape: box, params: {size: [20000, 20000, 20000]}, material: box, position: [0, 0, -100000]}
"""
CASES = {
    "zero_lights": ("", {}, {}),
    "one_light": ("  - {type: point, position: [0, 1, 2], radius: 4, intensity: 60}", {}, {}),
    "behind_camera": ("  - {type: point, position: [0, 3.87, 12.87], radius: 9, intensity: 800}", {}, {}),
    "radius_0": ("  - {type: point, position: [0, 0.5, 1.5], radius: 0, intensity: 10}\n"
                 "  - {type: spot, position: [0, 2, 0], radius: 0, intensity: 10}", {}, {}),
    "radius_1e4": ("  - {type: point, position: [0, 5, 0], radius: 10000, intensity: 50}", {}, {}),
    "froxel_boundary": (None, {}, {}),
    "camera_inside": ("  - {type: point, position: [0.2, 3.1, 9.8], radius: 20, intensity: 60}", {}, {}),
    "near_1e-4": ("  - {type: point, position: [0, 1, 2], radius: 4, intensity: 10}",
                  {"camera": "camera: {position: [0, 3, 10], look_at: [0, 0, 0], fov_y: 60, near: 0.0001}\n"}, {}),
    "spots": ("  - {type: spot, position: [-2, 3, 2], direction: [0.3, -1, -0.1], cone: [10, 30], radius: 8, intensity: 300}\n"
              "  - {type: spot, position: [2, 1, 6], direction: [-0.2, -0.3, -1], cone: [0, 5], radius: 15, intensity: 200}\n"
              "  - {type: spot, position: [0, 0.3, 3], direction: [0, 1, 0], cone: [80, 90], radius: 5, intensity: 20}", {},
              {"clusters.tile": "4", "clusters.slices": "16"}),  # froxels small against the cones
    "far_1e5": ("  - {type: point, position: [0, 12000, -88000], radius: 30000, intensity: 1e9}",
                {"camera": "camera: {position: [0, 3, 10], look_at: [0, 0, -100000], fov_y: 60, near: 0.1}\n",
                 "meshes": FAR_MESHES}, {}),
}


@pytest.mark.vulkan
@pytest.mark.parametrize("case", sorted(CASES))
def test_clustered_equals_all_lights(tmp_path, case):
    lights, scene_kw, params = CASES[case]
    if lights is None:
        lights = _boundary_light(tmp_path)
    scene = scene_file(tmp_path, lights, **scene_kw)
    _, clustered = render(scene, size=SIZE, params=params)
    _, every = render(scene, size=SIZE, params=params, mode="all_lights")
    a, b = srgb_codes(clustered), srgb_codes(every)
    assert np.abs(a - b).max() <= 1, f"{np.count_nonzero(a != b)} pixels differ, worst {np.abs(a - b).max()}"
    heat = clustered["light_heat"][..., 0]
    s = stats(clustered)
    assert s["overflowed_froxels"] == 0
    if case == "zero_lights":
        assert heat.max() == 0 and s["references"] == 0
    else:
        assert heat.max() >= 1 and s["references"] >= 1
    if case not in ("zero_lights", "radius_0"):
        assert a.max() >= 120, "the light should visibly light the geometry"
    if case == "behind_camera":
        cam = load_scene_data(scene, SIZE).camera(0)
        assert (cam.view @ np.append(np.array([0, 3.87, 12.87]) - cam.position, 1))[2] > 0  # behind: +z in view


@pytest.mark.vulkan
def test_65536_lights_overflow_is_reported_and_the_image_stays_right(tmp_path):
    lights = ("  - {generate: point, count: 65536, seed: 9, bounds: [[-6, 0.1, -6], [6, 2, 6]], radius: [0.2, 0.8],"
              " intensity: [0.02, 0.1]}")
    scene = scene_file(tmp_path, lights)
    size, params = (32, 24), {"clusters.max_indices": "4096", "clusters.tile": "16", "clusters.slices": "8"}
    _, clustered = render(scene, size=size, params=params)
    s = stats(clustered)
    assert s["capacity"] == 4096 and s["overflowed_froxels"] > 0 and s["references"] > 4096
    from rgraph.passes.cluster_report import stats_line

    assert "OVERFLOW" in stats_line(s) and "clusters.max_indices" in stats_line(s)
    assert clustered["light_heat"][..., 0].max() == 65536  # overflowed froxels shade every light
    _, every = render(scene, size=size, params=params, mode="all_lights")
    a, b = srgb_codes(clustered), srgb_codes(every)
    assert np.abs(a - b).max() <= 1 and a.max() >= 120
    _, bitmask = render(scene, size=size, params={**params, "clusters.list": "bitmask"})
    s = stats(bitmask)
    assert s["overflowed_froxels"] == 16 - 2 and s["references"] == 16 * 2048  # 2 froxels of 2,048 words fit
    assert np.abs(srgb_codes(bitmask) - b).max() <= 1


@pytest.mark.vulkan
def test_run_heatmap_timings_and_list_report(tmp_path, capsys):
    """rgraph run clustered --heatmap: a PNG of lights per pixel, the per-stage GPU times and the
    list statistics line; --heatmap on a graph without light_heat is one located error."""
    import json

    from rgraph.cli import main

    heat, timings = tmp_path / "heat.png", tmp_path / "t.json"
    args = ["run", "clustered", "--size", "64x36", "-p", "clusters.tile=16", "-p", "clusters.slices=8", "--validate"]
    assert main([*args, "--heatmap", str(heat), "--timings", str(timings)]) == 0
    err = capsys.readouterr().err
    assert "rgraph: 0 validation message(s)" in err and "rgraph: light lists:" in err and "OVERFLOW" not in err
    assert f"wrote heatmap {heat}" in err
    passes = json.loads(timings.read_text())["passes"]
    assert {"cluster_build", "light_assign", "forward", "heatmap"} <= set(passes)
    png = heat.read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 100
    assert main(["run", "surgery", "--size", "32x32", "--heatmap", str(tmp_path / "x.png")]) == 2
    assert "--heatmap needs an output image 'light_heat'" in capsys.readouterr().err


def test_heat_ramp_and_stats_line():
    from rgraph.passes.cluster_report import RAMP, heat_rgba, stats_line

    rgba, top = heat_rgba(np.array([[0.0, 1.0], [5.0, 10.0]]))
    assert top == 10 and rgba[0, 0, :3].tolist() == [0, 0, 0] and rgba[1, 1, :3].tolist() == RAMP[-1].tolist()
    assert np.all(rgba[..., 3] == 255) and rgba[1, 0, :3].tolist() == RAMP[2].tolist()
    assert "not built" in stats_line({"references": 0, "overflowed_froxels": 0, "longest_list": 0, "capacity": 0})
    line = stats_line({"references": 900, "overflowed_froxels": 3, "longest_list": 40, "capacity": 500})
    assert "OVERFLOW: 3 froxel(s)" in line and "at least 900" in line
