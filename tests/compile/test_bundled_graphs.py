"""Every bundled graph, as shipped (its own default scene), runs clean under validation on
lavapipe at a small size: zero validation or synchronization-validation messages (graphs with
raytrace passes too, under the layer setup installs; under Debian 12's 1.3.239, which crashes
creating ray tracing pipelines, they run without it); their images are checked against NumPy
references in tests/passes/test_rt_*.py."""

from __future__ import annotations

import numpy as np
import pytest

from rgraph.compiler.pipeline import compile_graph
from rgraph.resources import bundled_graphs

# Small-run params per graph: the graphs' defaults target a real GPU at 1920x1080.
SMALL = {
    "surgery": {"shadow.size": "256"},
    "surgery_clustered": {"shadow.size": "256", "clusters.tile": "16"},
    "clustered": {"clusters.tile": "16", "clusters.slices": "8"},
    "allocator_lines": {"alloc.meshes": "200", "alloc.segments": "10"},
    "rt_standalone": {"rt.sky_size": "16"},
    "rt_hybrid": {"rt.sky_size": "16"},
    "rt_hybrid_raster": {"rt.sky_size": "16"},
    "async_overlap": {"shadow.size": "256", "particles.count": "4096", "particles.substeps": "2"},
}


def test_every_bundled_graph_has_small_run_params():
    assert set(bundled_graphs()) == set(SMALL)


@pytest.mark.vulkan
@pytest.mark.parametrize("name", sorted(SMALL))
def test_bundled_graph_runs_clean(name):
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.executor import execute_plan
    from rgraph.vk.probe_rt import refuse_layer_for_ray_tracing

    plan = compile_graph(name, params=SMALL[name], size=(64, 36))
    try:
        refuse_layer_for_ray_tracing(plan)
        validate = True
    except ExecutionError:
        validate = False
    result = execute_plan(plan, validate=validate, frames=3, read_outputs=True)
    assert [m.text for m in result.messages] == []
    images = [r["name"] for r in plan["resources"] if r["lifetime"] == "output" and r["kind"] == "image"]
    assert images and all(np.isfinite(result.outputs[n]).all() for n in images)
    assert result.timings["total_ms"] is not None
