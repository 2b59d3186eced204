"""benchmarks/large_world.py (issue 6 item 4): its GPU transform pass and its CPU paths.

The figures are the benchmark's business (timings are never asserted); these tests check
that what it times is right: the float64 and camera-relative float32 vertex paths draw the
same picture (under validation, with shaderFloat64 enabled), both near and 1e12 m from the
origin, and the vectorized camera-relative matrices are bit for bit what the runtime uploads.
"""

from __future__ import annotations

import importlib.util
import math
import sys

import numpy as np
import pytest
from locations import ROOT

BENCH = ROOT / "benchmarks" / "large_world.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("large_world_bench", BENCH)
    module = importlib.util.module_from_spec(spec)
    sys.modules["large_world_bench"] = module
    spec.loader.exec_module(module)  # registers the large_world_transform pass
    return module


def test_vectorized_relative_matrices_equal_the_uploaded_draws(bench):
    from rgraph.scene import packing
    from rgraph.scene.build import load_scene_data

    scene = load_scene_data(bench.CCT, (64, 36))
    world, normals = bench.world_draws(scene, np.zeros(3))
    mine = bench.pack_models(bench.relative_models(world, scene.camera(0).position), normals)
    shipped = np.frombuffer(packing.draws_bytes(scene, 0), np.float32).reshape(len(world), -1)[:, :32]
    np.testing.assert_array_equal(mine, shipped)


def test_instanced_scene_has_ten_thousand_more_draws(bench):
    from rgraph.scene.build import load_scene_data

    base = load_scene_data(bench.CCT, (64, 36)).draw_count
    assert bench.instanced_scene((64, 36)).draw_count == base - 1 + 10_000


def test_cpu_costs_are_positive_and_naive_is_a_copy(bench):
    from rgraph.scene.build import load_scene_data

    costs = bench.cpu_costs(load_scene_data(bench.CCT, (64, 36)), 1e12, repeats=5)
    assert costs["draws"] > 0
    assert all(math.isfinite(costs[k]) and costs[k] > 0 for k in costs if k.endswith("_us"))


@pytest.mark.vulkan
@pytest.mark.parametrize("distance", [1e4, 1e12])
def test_float64_and_camera_relative_float32_draw_the_same_picture(bench, distance):
    bench.enable_float64()
    float64, _ = bench.has_float64()
    kw = dict(size=(96, 54), frames=2, instances=27, triangles=64, validate=True)
    rel = bench.gpu_run(0, distance, **kw)
    assert rel["messages"] == []
    covered = np.asarray(rel["image"])[..., :3].max(axis=-1) > 0.05
    assert 0.05 < covered.mean() < 0.9  # the spheres are in view
    assert rel["ms"] is not None and math.isfinite(rel["ms"]) and rel["ms"] > 0
    if not float64:
        pytest.skip("no shaderFloat64 on this device")
    f64 = bench.gpu_run(1, distance, **kw)
    assert f64["messages"] == []
    assert f64["ms"] is not None and math.isfinite(f64["ms"]) and f64["ms"] > 0
    differ = np.abs(np.asarray(rel["image"], np.float64) - np.asarray(f64["image"], np.float64)).max(axis=-1) > 0.02
    assert differ.mean() < 0.01  # at most edge pixels (sub-pixel differences at 1e12 m)


def test_table_rows_have_every_column(bench, capsys, tmp_path):
    out = tmp_path / "lw.json"
    assert bench.main(["--width", "64", "--height", "36", "--distances", "1e4,1e12", "--no-gpu",
                       "--cpu-repeats", "3", "--json", str(out)]) == 0
    import json

    data = json.loads(out.read_text())
    near, far = data["rows"]
    assert near["err_px_relative_f32"] < 0.01 and far["err_px_relative_f32"] < 0.01
    assert far["err_px_naive_f32"] > 1 or math.isinf(far["err_px_naive_f32"])
    assert near["err_px_f64"] < far["err_px_f64"]
    assert "distance" in capsys.readouterr().out
