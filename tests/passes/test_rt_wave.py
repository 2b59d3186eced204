"""The hybrid's wavefront ray tree (graphs/rt_hybrid.yaml, passes/raytrace_wave.py) on lavapipe,
on a scene of deep trees (tests/data/rt/wave_tir.yaml: facing mirrors, a rotated glass cube with
total internal reflection, a crystal sphere) at rt.max_depth 6, deeper than the graph's three
lists (levels 4 and 5 are walked in-thread by the last list's rays):

- every tree node is traced exactly once: each level's list holds as many rays as the NumPy
  float64 reference tree has nodes at that depth (a dropped or duplicated ray changes a count),
  and the image equals the stand-alone one (a dropped ray darkens a pixel, a duplicated one
  brightens it) and the reference's;
- full lists and full accumulators (tiny capacities) fall back to in-thread walks: same image;
- ``rt.wavefront: 0`` (the path of devices without 64-bit atomics): same image, empty lists;
- ``rt.wave_subgroup: 1`` (subgroup appends where the device has them): same lists and image;
- benchmarks/graphs/rt_hybrid_async.yaml (matte pixels on the async queue): same lists and image;
- the fixed-point accumulation is order-independent: two runs are bit-identical.
Every run is validated (validation + synchronization validation) and must log no message.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rt_helpers import rt_validates

from rgraph.compiler.pipeline import compile_graph
from rgraph.resources import builtin_passes
from rgraph.vk.errors import VulkanUnavailable

builtin_passes()
from rgraph.passes.rt_model import build_tables, sky_cubemap  # noqa: E402
from rgraph.passes.rt_ref import render  # noqa: E402

from rgraph.scene.build import load_scene_data  # noqa: E402

SCENE = TESTS / "data" / "rt" / "wave_tir.yaml"
SIZE = 24
DEPTH = 6
LISTS = ("rays_1_args", "rays_2_args", "rays_3_args")


def _run(graph: str, **params: str) -> dict:
    from rgraph.vk.executor import execute_plan

    wave = {"rt.wavefront": "1"} if graph == "rt_hybrid" else {}  # the tree by levels (graphs/rt_hybrid.yaml: 0)
    plan = compile_graph(graph, scene_path=SCENE, size=(SIZE, SIZE),
                         params={"rt.max_depth": str(DEPTH), **wave, **params},
                         extra_outputs=["ray_args", *LISTS] if graph != "rt_standalone" else [])
    try:
        result = execute_plan(plan, validate=rt_validates(), frames=1, read_outputs=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert result.messages == []
    return result.outputs


def _args(out: dict, name: str) -> np.ndarray:
    return np.frombuffer(out[name].tobytes()[:16], dtype=np.uint32)


def _rgb(out: dict) -> np.ndarray:
    return out["color"][..., :3].astype(np.float64)


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(1.0 / mse)


@pytest.fixture(scope="module")
def alone() -> np.ndarray:
    return _rgb(_run("rt_standalone"))


@pytest.mark.vulkan
def test_every_tree_node_is_traced_once_and_the_image_matches(alone):
    stats: dict = {"levels": {}}
    ref = render(build_tables(load_scene_data(SCENE, (SIZE, SIZE))), sky_cubemap(64), (SIZE, SIZE), DEPTH, stats)
    assert stats["tir"] > 0 and stats["levels"][DEPTH - 1] > 0  # the scene exercises TIR and the full depth
    out = _run("rt_hybrid")
    counts = [int(_args(out, name)[0]) for name in LISTS]
    assert counts == [stats["levels"][k] for k in (1, 2, 3)]
    assert not any(_args(out, name)[3] for name in LISTS)  # no overflow
    assert 0 < _args(out, "ray_args")[3] <= stats["levels"][1]  # pixels with children
    hybrid = _rgb(out)
    assert np.isfinite(hybrid).all()
    assert np.abs(hybrid - alone).max() < 2e-3 and psnr(alone, hybrid) > 70
    assert np.abs(hybrid - ref).max() < 0.01 and psnr(ref, hybrid) > 55
    assert np.array_equal(out["color"], _run("rt_hybrid")["color"])  # order-independent sums: bit-identical


@pytest.mark.vulkan
def test_full_lists_and_accumulators_fall_back_to_in_thread_walks(alone):
    out = _run("rt_hybrid", **{"rt.wave_rays": "8", "rt.wave_pixels": "150"})
    assert _args(out, "ray_args")[3] > 150  # more pixels with children than accumulators
    assert _args(out, "rays_1_args")[3] == 0 and _args(out, "rays_1_args")[0] <= 300  # list 1: 2 rays per slot
    assert _args(out, "rays_2_args")[3] == 1 and 0 < _args(out, "rays_2_args")[0] <= 8  # list 2 full
    assert np.abs(_rgb(out) - alone).max() < 2e-3 and psnr(alone, _rgb(out)) > 70


@pytest.mark.vulkan
def test_without_the_wavefront_the_shade_pass_walks_every_tree(alone):
    out = _run("rt_hybrid", **{"rt.wavefront": "0"})
    assert [int(_args(out, name)[0]) for name in ("ray_args", *LISTS)] == [0, 0, 0, 0]
    assert np.abs(_rgb(out) - alone).max() < 2e-3 and psnr(alone, _rgb(out)) > 70


@pytest.mark.vulkan
def test_subgroup_appends_give_the_same_lists_and_image(alone):
    """rt.wave_subgroup 1: one list atomic per subgroup where ray generation shaders have subgroup
    operations (a GPU), else (lavapipe) per-ray atomics; either way the same trees and image."""
    out = _run("rt_hybrid", **{"rt.wave_subgroup": "1"})
    assert [int(_args(out, name)[0]) for name in LISTS] == [int(_args(_run("rt_hybrid"), name)[0]) for name in LISTS]
    assert np.abs(_rgb(out) - alone).max() < 2e-3 and psnr(alone, _rgb(out)) > 70


@pytest.mark.vulkan
def test_the_async_variant_traces_the_same_trees(alone):
    """benchmarks/graphs/rt_hybrid_async.yaml: classify + level 0 of the listed pixels on the
    graphics queue, the matte pixels' shading on the compute queue, the same waves and resolve."""
    from locations import ROOT

    out = _run(str(ROOT / "benchmarks" / "graphs" / "rt_hybrid_async.yaml"))
    hybrid = _run("rt_hybrid")
    assert [int(_args(out, name)[0]) for name in LISTS] == [int(_args(hybrid, name)[0]) for name in LISTS]
    assert _args(out, "ray_args")[0] > 0  # classify's list: (count, 1, 1)
    assert np.abs(_rgb(out) - alone).max() < 2e-3 and psnr(alone, _rgb(out)) > 70
