"""Third round of outside-user inputs (FORMAT.md 5-7, tests/fixtures/unseen/*/r3_*), now that
``--validate`` covers ray tracing: new ray tracing graphs, splits over two logical devices and
stereo runs, under validation and synchronization validation. Each bug they found stays fixed:

- a ray query declared in the vertex stage only (``{usage: accel_read, stages: [vertex]}`` in
  a raster pass) was made by the probe in the fragment shader, outside the barrier's stages
  (two SYNC-HAZARD-READ-AFTER-WRITE messages); the probe now queries in each declared stage,
  and the simulation counts each stage's rays, like reads;
- ``--camera N`` with ``--devices``/``--split`` rendered camera 0: ``rgraph run`` never passed it
  to the split compile and ``compile`` dropped it from multi-device plans (``--sync naive`` and
  ``--schedule`` were dropped by ``run`` too, where ``compile`` refuses them, located);
- a multi-device plan file ran with ``--size``, ``--scene``, ``-p``, ``--split`` ... silently
  ignored and without ``rgraph check``'s hazard refusal, unlike a one-device plan file.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from rt_helpers import rt_validates
from test_unseen_inputs import _diagnostics, _g, _run, _s  # the first round's fixture helpers

from rgraph.cli import main

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


def test_a_multi_device_plan_keeps_the_camera(tmp_path: Path) -> None:
    plan = tmp_path / "split.json"
    assert main(["compile", "clustered", "--scene", _s("r3_rt_skinned_unique"), "--camera", "1", "--size", "16x12",
                 "--devices", "2", "--split", "sort-first", "-o", str(plan)]) == 0
    doc = json.loads(plan.read_text())
    assert doc["multi_device"]["devices"] == 2 and doc["camera"] == 1


def test_a_multi_device_plan_file_refuses_compile_flags_and_hazards(tmp_path: Path, capsys) -> None:
    plan = tmp_path / "split.json"
    assert main(["compile", "clustered", "--size", "16x12", "--devices", "2", "--split", "sort-last",
                 "-o", str(plan)]) == 0
    for flags in (["--camera", "1"], ["--split", "sort-first"], ["-p", "views=2"], ["--sync", "naive"]):
        rc, diags = _diagnostics(capsys, ["run", str(plan), "--devices", "0,0", *flags])
        assert rc == 2 and diags[0]["file"] == "<command line>", flags
        assert f"{flags[0]} only applies when compiling a graph" in diags[0]["message"]
    doc = json.loads(plan.read_text())
    victim = next(p for p in doc["passes"] if p["device"] == 0 and p["kind"] == "transfer" and p["barriers"])
    victim["barriers"] = victim["barriers"][1:]
    plan.write_text(json.dumps(doc))
    rc, diags = _diagnostics(capsys, ["run", str(plan), "--devices", "0,0"])
    assert rc == 2 and diags[0]["file"] == str(plan) and "rgraph check finds" in diags[0]["message"]


# ------------------------------------------------------------------ on the device
@vulkan
@pytest.mark.parametrize("mode", ["sort-first", "sort-last"])
def test_a_split_renders_the_chosen_camera(mode: str, tmp_path: Path, capsys) -> None:
    images = {}
    for name, extra in (("one", []), ("split", ["--devices", "0,0", "--split", mode])):
        out = tmp_path / f"{name}.png"
        rc, err = _run(capsys, ["clustered", "--scene", _s("r3_rt_skinned_unique"), "--camera", "1",
                                "--size", "16x12", "--out", str(out), *extra])
        assert rc == 0, err
        images[name] = out.read_bytes()
    assert images["one"] == images["split"]
    rc, err = _run(capsys, ["clustered", "--devices", "0,0", "--split", mode, "--schedule", "async-early"])
    assert rc == 2 and "--schedule async-early applies to one-device plans only" in err


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
    validate = rt_validates()  # else ray tracing runs unvalidated (tests/rt_helpers.py)
    rc, err = _run(capsys, [_g(graph), *(["--scene", _s(scene)] if scene else []), "--size", "16x12",
                            "--frames", "2", "--validate" if validate else "--check-data", *extra])
    assert rc == 0 and ("0 validation message(s)" in err or not validate), err
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
    validate = rt_validates() or not graph.startswith("rt_")
    rc, err = _run(capsys, [graph, "--scene", _s(scene), "--size", "16x12", *(["--validate"] if validate else []),
                            *extra])
    assert rc == 0 and ("0 validation message(s)" in err or not validate), err


@pytest.mark.vulkan
def test_a_device_index_out_of_range_names_both_flags(capsys) -> None:
    """``--devices 0,5`` on a one-device machine: the error said ``--device 5``, a flag not given."""
    rc, err = _run(capsys, ["surgery", "--devices", "0,99", "--split", "sort-first", "--size", "16x16"])
    assert rc == 2 and "device index 99 (--device / --devices) is out of range" in err, err


@pytest.mark.vulkan
def test_a_multi_device_plan_run_on_one_device_suggests_devices(tmp_path: Path, capsys) -> None:
    plan = tmp_path / "split.json"
    assert main(["compile", "surgery", "--size", "16x16", "--devices", "2", "--split", "sort-first",
                 "-o", str(plan)]) == 0
    rc, err = _run(capsys, [str(plan)])
    assert rc == 2 and "run a multi-device plan with one device per plan device (--devices 0,0)" in err, err
