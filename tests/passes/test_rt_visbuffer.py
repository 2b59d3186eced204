"""The compute visibility buffer (passes/raytrace_visbuffer.py) on lavapipe under validation and
synchronization validation (tests/pass_graphs/rt_visbuffer.yaml: its passes without the ray
tracing ones, which tests/passes/test_rt_hybrid.py runs), data-checked against the NumPy float64
reference of the camera rays (passes/rt_vis_ref.py): equal ids on >= 99% of the pixels, every
mismatch on a triangle or silhouette edge. Hard cases: tests/data/rt/vis_hard.yaml (1e6 m from
the origin, triangles crossing the camera plane or behind it, degenerate, sub-pixel and
screen-sized ones), the tile-job list or the setup records overflowing, and every triangle sent
to the tile jobs."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT, TESTS

from rgraph.compiler.pipeline import compile_graph
from rgraph.resources import builtin_passes
from rgraph.vk.errors import VulkanUnavailable

builtin_passes()
from rgraph.passes.raytrace_hybrid import decode_visibility, prim_bits  # noqa: E402
from rgraph.passes.raytrace_visbuffer import groups_for, triangle_starts  # noqa: E402
from rgraph.passes.rt_vis_ref import edge_pixels, visibility_reference  # noqa: E402

GRAPH = TESTS / "pass_graphs" / "rt_visbuffer.yaml"
TINY = ROOT / "graphs" / "scenes" / "rt_tiny.yaml"
HARD = TESTS / "data" / "rt" / "vis_hard.yaml"


def _visibility(scene, size, params=None, wide="1"):
    """The ids and the job list's header; ``wide``: rt.vis_atomic64 (1: the one-pass 64-bit path,
    checked to have run: the ids are the packed keys' low halves; 0: the two-pass 32-bit path,
    which leaves vis_keys alone)."""
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(str(GRAPH), scene_path=scene, size=size, params={**(params or {}), "rt.vis_atomic64": wide},
                         extra_outputs=["vis_keys"])
    try:
        result = execute_plan(plan, validate=True, frames=2, read_outputs=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert [m.text for m in result.messages] == []
    header = np.frombuffer(result.outputs["vis_jobs"].tobytes()[:8], dtype=np.uint32)  # job count, overflow
    ids = result.outputs["visibility"][..., 0]
    keys = np.frombuffer(result.outputs["vis_keys"].tobytes()[:8 * ids.size], dtype=np.uint64).reshape(ids.shape)
    if wide == "1":
        assert keys.any() and np.array_equal(keys & 0xFFFFFFFF, ids)
    return ids, header


def _reference(scene, size):
    from rgraph.scene.build import load_scene_data

    data = load_scene_data(scene, size)
    return visibility_reference(data, size, prim_bits(data)), prim_bits(data)


def _assert_agrees(ids, ref):
    equal = ids == ref
    assert equal.mean() >= 0.99, equal.mean()
    assert not (~equal & ~edge_pixels(ref)).any(), np.argwhere(~equal & ~edge_pixels(ref))[:5]


@pytest.mark.vulkan
@pytest.mark.parametrize("wide", ["1", "0"])
def test_tiny_scene_matches_the_camera_rays(wide):
    size = (48, 40)
    ids, args = _visibility(TINY, size, wide=wide)
    ref, _bits = _reference(TINY, size)
    _assert_agrees(ids, ref)
    assert 0 < (ids > 0).mean() < 1 and args[1] == 0  # some sky; no overflow


@pytest.mark.vulkan
@pytest.mark.parametrize("wide", ["1", "0"])
def test_hard_cases_and_the_tile_job_paths_give_the_same_ids(wide):
    size = (64, 48)
    ref, bits = _reference(HARD, size)
    instance, _prim = decode_visibility(ref, bits)
    assert {-1, 0, 1, 5, 6} <= set(np.unique(instance).tolist())  # sky, floor, crossing box, sphere, wall
    ids, args = _visibility(HARD, size, wide=wide)
    _assert_agrees(ids, ref)
    assert args[0] > 0 and args[1] == 0  # the floor and wall went to tile jobs
    full, full_args = _visibility(HARD, size, {"rt.vis_job_bytes": "80"}, wide=wide)  # room for 8 jobs: overflow
    assert full_args[1] == 1 and full_args[0] <= 8
    every, every_args = _visibility(HARD, size, {"rt.vis_big_pixels": "1"}, wide=wide)  # nearly all triangles as tiles
    assert every_args[0] > args[0] and every_args[1] == 0
    few, few_args = _visibility(HARD, size, {"rt.vis_tri_bytes": "160"}, wide=wide)  # 2 setup records: overflow
    assert few_args[1] == 1
    assert np.array_equal(full, ids) and np.array_equal(every, ids) and np.array_equal(few, ids)


def test_triangle_starts_and_dispatch_shape():
    from types import SimpleNamespace as NS

    data = NS(meshes=[NS(data=NS(triangle_count=5), positions=[0, 1]), NS(data=NS(triangle_count=3), positions=[0])])
    assert triangle_starts(data).tolist() == [0, 5, 10]
    assert groups_for(1) == (1, 1) and groups_for(64 * 32768 + 1) == (32768, 2)
