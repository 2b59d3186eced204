"""The allocator experiment's graph and ``mesh_lines`` pass: layout, camera, and real runs on lavapipe."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from locations import ROOT

from rgraph.compiler.pipeline import compile_graph, frontend
from rgraph.spec.scene import load_scene

ROOT = ROOT
GRAPH = ROOT / "graphs" / "allocator_lines.yaml"
SCENE = ROOT / "graphs" / "scenes" / "lines10k.yaml"
TINY = {"alloc.meshes": "200", "alloc.segments": "10", "alloc.deformable_fraction": "0.25"}
SIZE = (160, 96)


def mesh_lines():
    from rgraph.impl import lookup

    return lookup("mesh_lines")


def module():
    import sys

    mesh_lines()
    return sys.modules[mesh_lines().__module__]


def test_graph_validates_with_its_scene():
    front = frontend(str(GRAPH))
    assert front.scene is not None and front.scene.name == "lines10k"
    assert [p.name for p in front.spec.passes] == ["lines"]


def test_scene_layout_is_the_documented_grid():
    m = module()
    layout = m.build_layout(load_scene(SCENE).model)
    assert len(layout) == 10_000
    assert int(layout.deformable.sum()) == 1_000
    assert set(layout.segments.tolist()) == {100}
    assert np.ptp(layout.positions[:, 0]) == pytest.approx(99.0)
    assert np.ptp(layout.positions[:, 2]) == pytest.approx(99.0)


def test_param_overrides_sample_spread_and_stack():
    m = module()
    scene = load_scene(SCENE).model
    small = m.build_layout(scene, meshes=200, segments=10, deformable_fraction=0.25)
    assert len(small) == 200 and set(small.segments.tolist()) == {10}
    assert int(small.deformable.sum()) == 50
    assert min(np.ptp(small.positions[:, 0]), np.ptp(small.positions[:, 2])) > 80  # the whole grid, not a strip
    from_scene = m.build_layout(scene, meshes=200)
    assert 0 < int(from_scene.deformable.sum()) < 200  # the scene's own deformable rows
    big = m.build_layout(scene, meshes=25_000, deformable_fraction=0.0)
    assert len(big) == 25_000 and not big.deformable.any()
    assert len({tuple(p) for p in big.positions.round(6)}) == 25_000  # extra meshes stacked, never coincident


def test_helix_vertices_are_a_line_list():
    m = module()
    layout = m.build_layout(None, meshes=3, segments=5, deformable_fraction=0.0)
    verts = m.helix_vertices(layout, np.arange(3))
    assert [v.shape for v in verts] == [(10, 4)] * 3
    v = verts[1]
    np.testing.assert_allclose(v[1:-1:2, :3], v[2::2, :3])  # segment k ends where k + 1 starts
    r = np.hypot(v[:, 0] - layout.positions[1, 0], v[:, 2] - layout.positions[1, 2])
    np.testing.assert_allclose(r, layout.radius[1], rtol=1e-5)


def test_view_projection_centres_the_target_with_reversed_depth():
    m = module()
    camera = load_scene(SCENE).model.camera
    vp = m.view_projection(camera, 16 / 9)
    clip = vp @ np.array([*camera.look_at, 1.0])
    assert clip[0] / clip[3] == pytest.approx(0, abs=1e-9) and clip[1] / clip[3] == pytest.approx(0, abs=1e-9)
    near_point = np.array(camera.position) + camera.near * (np.array(camera.look_at) - camera.position) / \
        np.linalg.norm(np.array(camera.look_at) - camera.position)
    near = vp @ np.array([*near_point, 1.0])
    assert near[2] / near[3] == pytest.approx(1.0)
    assert 0 < clip[2] / clip[3] < 0.01  # far away: depth towards 0 (reversed-Z)
    above = vp @ np.array([camera.look_at[0], camera.look_at[1] + 5, camera.look_at[2], 1.0])
    assert above[1] / above[3] < 0  # Vulkan clip space: up is -y


def test_wobble_writes_every_mesh_through_strided_runs_and_nothing_else():
    """The per-frame writer against plain per-mesh slices, over runs, gaps, odd strides and blocks."""
    from rgraph.vk.mesh_pool import Allocation, MemoryBlock, PoolBuffer

    m = module()
    layout = m.build_layout(None, meshes=9, segments=3, deformable_fraction=1.0)
    layout.segments[6:] = 5  # a different vertex count breaks a run
    meshes = np.arange(9)
    base = m.helix_vertices(layout, meshes)
    blocks = [MemoryBlock(handle=i, size=4096, type_index=0, tlsf=None) for i in range(3)]
    mapped = {id(b): np.full((256, 4), -7.0, np.float32) for b in blocks}
    #         block, first row: a run of 3 at stride 9, a gap, a run of 2 at stride 6, a lone mesh, another block
    where = [(0, 0), (0, 9), (0, 18), (0, 40), (0, 46), (1, 3), (1, 20), (2, 0), (2, 10)]
    buffers = [PoolBuffer(handle=k, allocation=Allocation(blocks[b], row * 16, 160), capacity=160, used=0,
                          dynamic=True) for k, (b, row) in enumerate(where)]

    class Pool:
        def rows(self, buf):
            return mapped[id(buf.allocation.block)]

    wobble = m._Wobble(base, layout, meshes)
    wobble.bind(0, Pool(), buffers)
    assert len(wobble.runs[0]) < 9  # some meshes share a strided run
    wobble.fill(0)
    wobble.write(5, 0)
    x = wobble.x(5)
    written = {id(b): np.zeros(256, bool) for b in blocks}
    for k, (b, row) in enumerate(where):
        want = base[k].copy()
        want[:, 0] = x[wobble.starts[k]:wobble.starts[k] + len(want)]
        got = mapped[id(blocks[b])][row:row + len(want)]
        np.testing.assert_array_equal(got, want)
        written[id(blocks[b])][row:row + len(want)] = True
    for b in blocks:
        assert np.all(mapped[id(b)][~written[id(b)]] == -7.0)  # gaps between buffers untouched
    assert not np.allclose(wobble.x(5), wobble.x(6))


def reference_mask(layout, vertices, size, vp, dilate):
    """Pixels within ``dilate`` of any point sampled along the lines (projected by NumPy)."""
    w, h = size
    mask = np.zeros((h, w), bool)
    hits = []
    for v in vertices:
        a, b = v[0::2, :3].astype(np.float64), v[1::2, :3].astype(np.float64)
        for t in np.linspace(0, 1, 5):
            p = a + (b - a) * t
            clip = np.c_[p, np.ones(len(p))] @ vp.T
            ndc = clip[:, :2] / clip[:, 3:4]
            px = np.floor((ndc[:, 0] + 1) / 2 * w).astype(int)
            py = np.floor((ndc[:, 1] + 1) / 2 * h).astype(int)
            ok = (px >= 0) & (px < w) & (py >= 0) & (py < h) & (clip[:, 3] > 0)
            hits.append(np.c_[px[ok], py[ok]])
    pts = np.concatenate(hits)
    for dx in range(-dilate, dilate + 1):
        for dy in range(-dilate, dilate + 1):
            x, y = np.clip(pts[:, 0] + dx, 0, w - 1), np.clip(pts[:, 1] + dy, 0, h - 1)
            mask[y, x] = True
    return mask


@pytest.mark.vulkan
def test_tiny_runs_clean_same_picture_for_every_block_size(tmp_path):
    from rgraph.vk.executor import execute_plan

    m = module()
    images, reports = {}, {}
    for block in (0, 4):
        report = tmp_path / f"report{block}.json"
        plan = compile_graph(GRAPH, size=SIZE, params={**TINY, "alloc.block_mib": str(block),
                                                        "alloc.report": str(report)})
        result = execute_plan(plan, validate=True, frames=3, read_outputs=True)
        assert [msg.text for msg in result.messages] == []
        assert result.timings["passes"]["lines"] is not None
        images[block] = result.outputs["color"]
        reports[block] = json.loads(report.read_text())
    rigid, deformable = 150, 50
    dedicated = reports[0]
    assert (dedicated["rigid"], dedicated["deformable"]) == (rigid, deformable)
    assert dedicated["allocations"] == dedicated["dedicated"] == rigid + 2 * deformable  # 2 frames in flight
    assert dedicated["allocated_bytes"] == dedicated["bound_bytes"]
    blocks = reports[4]
    assert blocks["dedicated"] == 0 and 1 <= blocks["allocations"] == blocks["blocks"] <= 2
    assert blocks["allocated_bytes"] == blocks["allocations"] * 4 * (1 << 20)
    for r in reports.values():
        assert r["allocations_after_destroy"] == 0
        assert r["draws_per_frame"] == 200 and r["update_frames"] == 3
        assert r["used_bytes"] == 16 * 20 * (rigid + 2 * deformable)
        deform_capacity = math.ceil(16 * 20 * 1.5 / 16) * 16
        assert r["bound_bytes"] >= 16 * 20 * rigid + 2 * deformable * deform_capacity
    # the allocator must not change the picture
    np.testing.assert_array_equal(images[0], images[4])
    # lines are where NumPy projects them (deformable meshes wobble: a wider tolerance)
    img = images[4]
    background = np.array([0.02, 0.02, 0.03])
    lit = np.abs(img[..., :3] - background).max(axis=-1) > 0.05
    assert 0.003 < lit.mean() < 0.5
    scene = load_scene(SCENE).model
    layout = m.build_layout(scene, 200, 10, 0.25)
    vp = m.view_projection(scene.camera, SIZE[0] / SIZE[1])
    everything = m.helix_vertices(layout, np.arange(200))
    assert (lit & ~reference_mask(layout, everything, SIZE, vp, dilate=2)).sum() <= 0.01 * lit.sum()
    rigid_only = [v for v, d in zip(everything, layout.deformable, strict=True) if not d]
    where = reference_mask(layout, rigid_only, SIZE, vp, dilate=0)
    near_lit = lit.copy()
    near_lit[1:] |= lit[:-1]
    near_lit[:-1] |= lit[1:]
    near_lit[:, 1:] |= near_lit[:, :-1]
    near_lit[:, :-1] |= near_lit[:, 1:]
    assert (where & near_lit).sum() >= 0.8 * where.sum()


@pytest.mark.vulkan
def test_deformable_meshes_move_between_frames():
    from rgraph.vk.executor import execute_plan

    params = {**TINY, "alloc.deformable_fraction": "1.0", "alloc.block_mib": "16"}
    frames = [execute_plan(compile_graph(GRAPH, size=SIZE, params=params), validate=True, frames=n,
                           read_outputs=True) for n in (1, 4)]
    assert all(r.messages == [] for r in frames)
    assert not np.array_equal(frames[0].outputs["color"], frames[1].outputs["color"])


@pytest.mark.vulkan
def test_over_the_allocation_limit_is_a_clear_error_and_blocks_fit(tmp_path):
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.executor import execute_plan

    report = tmp_path / "over.json"
    limited = {**TINY, "alloc.max_allocations": "100", "alloc.report": str(report)}
    plan = compile_graph(GRAPH, size=SIZE, params={**limited, "alloc.block_mib": "0"})
    with pytest.raises(ExecutionError, match=r"251 live device-memory allocations needed, but the limit is 100"):
        execute_plan(plan, validate=True)
    data = json.loads(report.read_text())
    assert data["allocations_needed"] == 251 and data["limit"] == 100 and "error" in data
    ok = execute_plan(compile_graph(GRAPH, size=SIZE, params={**limited, "alloc.block_mib": "4"}), validate=True)
    assert ok.messages == []


@pytest.mark.vulkan
def test_cli_reports_the_limit_without_a_traceback(capsys):
    from rgraph.cli import main

    code = main(["run", str(GRAPH), "--size", "32x32", "-p", "alloc.meshes=50", "-p", "alloc.segments=2",
                 "-p", "alloc.block_mib=0", "-p", "alloc.max_allocations=10"])
    err = capsys.readouterr().err
    assert code == 2
    assert "allocations needed, but the limit is 10" in err and "Traceback" not in err


def test_camera_relative_vertices_far_from_the_origin():
    """Helices 1e7 m from the origin project as they do at the origin (vertices and view are
    camera-relative; world-space float32 vertices collapsed them to a few lines)."""
    import types

    m = module()

    def clip(offset: float) -> np.ndarray:
        layout = m.build_layout(None, meshes=4, segments=8, deformable_fraction=0.0)
        layout.positions[:, [0, 2]] += offset
        camera = types.SimpleNamespace(position=(offset, 3.0, offset + 6.0), look_at=(offset, 0.0, offset),
                                       up=(0.0, 1.0, 0.0), fov_y=50.0, near=0.1)
        eye = m.camera_position(camera)
        verts = np.concatenate(m.helix_vertices(layout, np.arange(4), eye))
        vp = m.view_projection(camera, 16 / 9, eye).astype(np.float32)
        c = np.c_[verts[:, :3], np.ones(len(verts), np.float32)] @ vp.T
        return c[:, :3] / c[:, 3:]

    np.testing.assert_allclose(clip(1e7), clip(0.0), atol=1e-4)


def test_view_projection_looking_along_up_is_finite():
    import types

    m = module()
    camera = types.SimpleNamespace(position=(0.0, 5.0, 0.0), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                                   fov_y=50.0, near=0.1)
    vp = m.view_projection(camera, 1.0)
    assert np.isfinite(vp).all()
    below = vp @ np.array([0.0, 0.0, 0.0, 1.0])
    assert below[0] / below[3] == pytest.approx(0, abs=1e-9) and below[1] / below[3] == pytest.approx(0, abs=1e-9)
