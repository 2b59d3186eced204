"""Third round of outside-user inputs (FORMAT.md 5-7, tests/fixtures/unseen/*/r3_*), now that
``--validate`` covers ray tracing: new ray tracing graphs, splits over two logical devices and
stereo runs, under validation and synchronization validation. Each bug they found stays fixed:

- a ray query declared in the vertex stage only (``{usage: accel_read, stages: [vertex]}`` in
  a raster pass) was made by the probe in the fragment shader, outside the barrier's stages
  (two SYNC-HAZARD-READ-AFTER-WRITE messages); the probe now queries in each declared stage,
  and the simulation counts each stage's rays, like reads.
"""

from __future__ import annotations

import pytest
from test_unseen_inputs import _g, _run, _s  # the first round's fixture helpers

vulkan = pytest.mark.vulkan


# ------------------------------------------------------------------ device-free
def test_ray_queries_are_made_in_the_declared_raster_stages() -> None:
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.probe_glsl import generate

    plan = compile_graph(_g("r3_rt_query_stages"), size=(8, 6))
    resources = {r["name"]: r for r in plan["resources"]}
    queries = {}
    for p in plan["passes"]:
        if p["kind"] == "raster":
            sources = generate(p, resources, (8, 6)).sources
            queries[p["name"]] = tuple(sources[s].count("rayQueryInitializeEXT") for s in ("vert", "frag"))
    assert queries == {"draw": (3, 0), "overlay": (3, 3)}  # the probe's three rays per stage


# ------------------------------------------------------------------ on the device
RUNS = {  # id: (graph, scene or None, extra arguments)
    "query_vertex": ("r3_rt_query_vertex", None, []),
    "query_stages_sort_last": ("r3_rt_query_stages", "r3_rt_skinned_unique", ["--devices", "0,0",
                                                                               "--split", "sort-last"]),
    "alias_pair": ("r3_rt_alias_pair", "r3_rt_skinned_unique", []),
    "indirect_transfer": ("r3_rt_indirect_transfer", None, []),
    "war_cross_queue_async_early": ("r3_rt_war_cross_queue", None, ["--schedule", "async-early"]),
    "three_traces_mips_sort_first": ("r3_rt_three_traces_mips", None, ["--devices", "0,0", "--split",
                                                                        "sort-first"]),
    "uniform_async_sort_last": ("r3_rt_uniform_async", "r3_rt_skinned_unique", ["--devices", "0,0",
                                                                                 "--split", "sort-last"]),
    "optional_trace_culled": ("r3_rt_optional_trace", "r3_tiny_surgery", []),
    "optional_trace_kept": ("r3_rt_optional_trace", "r3_rt_skinned_unique", ["--camera", "1"]),
}


@vulkan
@pytest.mark.parametrize("case", sorted(RUNS))
def test_round3_fixtures_run_clean_under_validation(case: str, capsys) -> None:
    graph, scene, extra = RUNS[case]
    rc, err = _run(capsys, [_g(graph), *(["--scene", _s(scene)] if scene else []), "--size", "16x12",
                            "--frames", "2", "--validate", *extra])
    assert rc == 0 and "0 validation message(s)" in err, err
    assert "data check ok" in err, err


BUNDLED = {  # id: (bundled graph, scene, extra arguments): stereo and ray tracing over two devices
    "rt_hybrid_raster_sort_last": ("rt_hybrid_raster", "r3_rt_skinned_unique", ["--camera", "1", "--devices",
                                                                                 "0,0", "--split", "sort-last"]),
    "surgery_views2_sort_last": ("surgery", "r3_tiny_surgery", ["-p", "views=2", "--devices", "0,0",
                                                                "--split", "sort-last"]),
}


@vulkan
@pytest.mark.parametrize("case", sorted(BUNDLED))
def test_bundled_graphs_on_round3_scenes_run_clean_under_validation(case: str, capsys) -> None:
    graph, scene, extra = BUNDLED[case]
    rc, err = _run(capsys, [graph, "--scene", _s(scene), "--size", "16x12", "--validate", *extra])
    assert rc == 0 and "0 validation message(s)" in err, err
