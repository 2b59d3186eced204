"""Graphs and scenes written from FORMAT.md by an outside user (tests/fixtures/unseen), through
the command line: every fixture validates, compiles and passes ``rgraph check``; the device runs
are clean under validation and synchronization validation (raytrace passes too, since session
21's layer) and each bug these inputs found stays fixed:

- a compute or raster probe pass reading an accel (ray queries, FORMAT.md 5) was refused at run
  time; it now queries the probe's rays, and a wrong ray fails the data check;
- a probe trace of an accel over the scene's geometry failed the data check (the simulation
  assumed the probe geometry); it is now unchecked;
- ``validate`` passed a persistent scene accel with no meshes to build it from, ``compile``
  refused it;
- unknown keys in a scene's camera/cameras/materials/instances/decals listed the top-level keys;
- ``views`` outside 1..2 on a scene graph was an unlocated run-time error after compiling;
- FORMAT.md section 1's own ``layers: "${scene.shadow_lights}"`` / ``bytes: "${scene.lights} * 64"``
  failed on any scene without them, although only removed passes and optional reads use them;
- the sort-last composite of layered images (``views=2``) broke validation and both eyes.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from locations import ROOT, TESTS
from rt_helpers import rt_validates

from rgraph.cli import main

FIXTURES = TESTS / "fixtures" / "unseen"
GRAPHS = sorted((FIXTURES / "graphs").glob("*.yaml"))
SCENES = sorted((FIXTURES / "scenes").glob("*.yaml"))
vulkan = pytest.mark.vulkan


def _g(name: str) -> str:
    return str(FIXTURES / "graphs" / f"{name}.yaml")


def _s(name: str) -> str:
    return str(FIXTURES / "scenes" / f"{name}.yaml")


def _diagnostics(capsys, argv: list[str]) -> tuple[int, list[dict]]:
    capsys.readouterr()
    rc = main([*argv, "--json"])
    return rc, json.loads(capsys.readouterr().out)["diagnostics"]


# ------------------------------------------------------------------ device-free
@pytest.mark.parametrize("graph", GRAPHS, ids=lambda p: p.stem)
def test_every_fixture_graph_validates_compiles_and_checks(graph: Path, tmp_path: Path, capsys) -> None:
    scene = _s("deformable_rt")  # meshes, a light, a reflective material, a deformable mesh
    assert main(["validate", str(graph), "--scene", scene]) == 0
    plan = tmp_path / "plan.json"
    assert main(["compile", str(graph), "--scene", scene, "--size", "24x16", "-o", str(plan)]) == 0
    assert main(["check", str(plan)]) == 0
    assert "Traceback" not in capsys.readouterr().err


@pytest.mark.parametrize("scene", SCENES, ids=lambda p: p.stem)
def test_every_fixture_scene_validates_with_a_ray_traced_and_a_clustered_graph(scene: Path, capsys) -> None:
    for graph in (_g("rt_two_accels"), _g("cluster_like"), "clustered"):
        assert main(["validate", graph, "--scene", str(scene)]) == 0, graph
    assert "error" not in capsys.readouterr().err


def test_validate_refuses_a_scene_accel_with_no_meshes_like_compile(capsys) -> None:
    """rt_refit's persistent accel is built at load from the scene; the bare scene has none."""
    for command in ("validate", "compile"):
        rc, diags = _diagnostics(capsys, [command, _g("rt_refit"), "--scene", _s("bare")])
        assert rc == 2 and [(d["line"], d["col"]) for d in diags] == [(5, 3)], (command, diags)
        assert "no meshes to build it from" in diags[0]["message"]


def test_scene_unknown_keys_list_the_keys_of_their_own_mapping(tmp_path: Path, capsys) -> None:
    scene = tmp_path / "keys.yaml"
    scene.write_text("scene: 1\n"
                     "camera: {position: [0, 0, 3], look_at: [0, 0, 0], fovy: 40}\n"
                     "cameras: [{position: [0, 0, 3], look_at: [0, 0, 0], nearr: 1}]\n"
                     "materials: {m: {roughnes: 1}}\n"
                     "meshes: [{shape: box, material: m, instances: {grid: [1, 1, 1], spacing: 1, jitter: 2}}]\n"
                     "decals: [{material: m, position: [0, 0, 0], size: [1, 1, 1], angle: 3}]\n")
    rc, diags = _diagnostics(capsys, ["validate", _g("rt_min"), "--scene", str(scene)])
    assert rc == 2
    got = {(d["line"], d["col"]): d["message"] for d in diags}
    assert "did you mean 'fov_y'?" in got[(2, 51)] and "valid keys: position, look_at, up, fov_y, near" in got[(2, 51)]
    assert "did you mean 'near'?" in got[(3, 53)]
    assert "did you mean 'roughness'?" in got[(4, 17)] and "base_color" in got[(4, 17)]
    assert "valid keys: grid, spacing, count, seed, bounds" in got[(5, 77)]
    assert "valid keys: material, position, size, rotation" in got[(6, 62)]
    assert not any("valid keys: scene, name" in m for m in got.values())


def test_views_out_of_range_is_refused_before_compiling_and_located(tmp_path: Path, capsys) -> None:
    rc, diags = _diagnostics(capsys, ["validate", "clustered", "-p", "views=3"])
    assert rc == 2 and diags[0]["file"] == "<command line>" and "'views'" in diags[0]["message"]
    assert "must be in 1..2, got 3" in diags[0]["message"]
    graphs = tmp_path / "graphs"  # the graph's own params: the error points at the value
    graphs.mkdir()
    (graphs / "scenes").symlink_to(ROOT / "graphs" / "scenes")
    text = (ROOT / "graphs" / "clustered.yaml").read_text()
    assert "\n  views: 1 " in text
    (graphs / "clustered.yaml").write_text(text.replace("\n  views: 1 ", "\n  views: 3 "))
    rc, diags = _diagnostics(capsys, ["validate", str(graphs / "clustered.yaml")])
    line = text[: text.index("\n  views: 1 ") + 1].count("\n") + 1
    assert rc == 2 and (diags[0]["line"], diags[0]["col"]) == (line, 10), diags
    assert main(["validate", "clustered", "-p", "views=2"]) == 0


def test_counts_of_absent_scene_features_are_errors_only_where_used(tmp_path: Path, capsys) -> None:
    graph = _g("spec_section1_probe")
    plan = tmp_path / "plan.json"
    assert main(["compile", graph, "--scene", _s("one_instance_no_lights"), "--size", "16x8", "-o", str(plan)]) == 0
    doc = json.loads(plan.read_text())
    assert [(c["pass"], c["resources"], c["bytes"]) for c in doc["culled"]] == [
        ("shadow", ["shadow_maps"], 0), ("light_fill", ["lights"], 0)]
    assert {d["resource"] for d in doc["dropped_reads"]} == {"shadow_maps", "lights"}
    assert "shadow_maps" not in {r["name"] for r in doc["resources"]}
    text = Path(graph).read_text()
    kept = tmp_path / "kept.yaml"  # the shadow pass runs anyway: its 0 layers are an error again
    kept.write_text(text.replace("    requires: [shadow_lights]\n", ""))
    rc, diags = _diagnostics(capsys, ["validate", str(kept), "--scene", _s("opaque_only")])
    assert rc == 2 and [(d["line"], d["col"]) for d in diags] == [(11, 25)] and "got 0" in diags[0]["message"]
    literal = tmp_path / "literal.yaml"  # a literal 0 is an error even where nothing uses it
    literal.write_text(text.replace('layers: "${scene.shadow_lights}"', "layers: 0"))
    assert main(["validate", str(literal), "--scene", _s("deformable_rt")]) == 2


def test_the_simulation_leaves_scene_geometry_traces_unchecked(memory) -> None:
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.probe.simulate import simulate

    graph = _g("rt_persistent_scene_probe_trace")
    scene_plan = compile_graph(graph, scene_path=_s("opaque_only"), size=(8, 8), memory=memory)
    assert next(r for r in scene_plan["resources"] if r["name"] == "tlas")["accel"]["geometry"] == "scene"
    assert simulate(scene_plan, 2)[("color", 0, 0)] is None
    probe_plan = compile_graph(graph, size=(8, 8), memory=memory)  # no scene: the probe geometry
    assert simulate(probe_plan, 2)[("color", 0, 0)] is not None


def test_ray_queries_need_the_device_feature() -> None:
    from types import SimpleNamespace

    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.probe_rt import probe_class

    plan_pass = {"name": "query", "kind": "compute", "accesses": [{"resource": "tlas", "usage": "accel_read"}]}
    device = SimpleNamespace(name="gpu", enabled_features=set())
    with pytest.raises(ExecutionError, match="has no ray queries"):
        probe_class(plan_pass, device)
    assert probe_class(plan_pass, SimpleNamespace(name="gpu", enabled_features={"rayQuery"})).__name__ == "Probe"


BAD = {  # malformed ray tracing graphs (tests/fixtures/unseen/bad): (line, col, message start) each
    "accel_geom_bad": [(4, 33, "unknown geometry 'everything' (valid: scene, probe)")],
    "accel_kind_typo": [(4, 16, "unknown resource kind 'acceleration'"), (8, 11, "unknown pass kind 'raytracing'")],
    "accel_no_build": [(9, 19, "pass 'trace' reads 'tlas' before any pass writes it")],
    "accel_read_on_image": [(13, 36, "usage 'accel_read' needs an accel, but 'src' is an image")],
    "accel_rw": [(11, 20, "pass 'both' uses overlapping parts of 'tlas'")],
    "accel_selector": [(12, 13, "'tlas' is an accel: it has no mips or layers")],
    "accel_stages": [(12, 19, "stages ['fragment'] are not stages of a raytrace pass")],
    "accel_twice": [(7, 55, "pass 'build' uses 'tlas' as accel_build twice")],
    "accel_with_size": [(4, 23, "unknown key 'size' in resource 'tlas'"), (4, 37, "unknown key 'format'")],
    "accel_wrong_usage": [(9, 20, "usage 'storage_write' needs a buffer or an image, but 'tlas' is an accel")],
    "build_in_raster": [(9, 20, "usage 'accel_build' is not possible in a raster pass")],
    "build_in_raytrace": [(9, 20, "usage 'accel_build' is not possible in a raytrace pass")],
    "build_transfer_queue": [(9, 12, "a compute pass cannot run on the transfer queue")],
    "rt_impl_unknown": [(13, 11, "no pass implementation named 'no_such_tracer'")],
    "rt_requires_bad": [(12, 16, "unknown scene feature 'reflective_material'; did you mean 'reflective_materials'?")],
    "trace_color_attach": [(13, 19, "usage 'color_attachment' is not possible in a raytrace pass")],
    "trace_transfer_queue": [(12, 12, "a raytrace pass cannot run on the transfer queue")],
    "transfer_accel": [(13, 19, "usage 'transfer_src' needs a buffer or an image, but 'tlas' is an accel")],
}


def test_every_bad_fixture_is_listed() -> None:
    assert sorted(p.stem for p in (FIXTURES / "bad").glob("*.yaml")) == sorted(BAD)


@pytest.mark.parametrize("name", sorted(BAD))
def test_malformed_ray_tracing_graphs_are_located(name: str, capsys) -> None:
    path = str(FIXTURES / "bad" / f"{name}.yaml")
    # impls: compile leaves them to the runtime; validate and run (before the device opens) look them up
    commands = ["validate", "run"] if name == "rt_impl_unknown" else ["validate", "compile"]
    for command in commands:
        rc, diags = _diagnostics(capsys, [command, path])
        assert rc == 2, command
        assert [(d["file"], d["line"], d["col"]) for d in diags] == [(path, ln, col) for ln, col, _ in BAD[name]]
        for d, (_, _, start) in zip(diags, BAD[name], strict=True):
            assert d["message"].startswith(start), d["message"]


# ------------------------------------------------------------------ on the device
def _run(capsys, argv: list[str]) -> tuple[int, str]:
    capsys.readouterr()
    rc = main(["run", *argv])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return rc, err


RUNS = {  # id: (graph, scene, extra arguments)
    "ray_query_compute": ("rt_ray_query_compute", "far_world", []),
    "ray_query_raster_async": ("rt_ray_query_raster", "one_instance_no_lights", []),
    "ray_query_sort_first": ("rt_ray_query_raster", "presets", ["--devices", "0,0", "--split", "sort-first",
                                                                 "--camera", "1"]),
    "spec_section1_no_shadow_lights": ("spec_section1_probe", "opaque_only", []),
    "ray_query_layers_sort_last": ("rt_ray_query_layers", "deformable_rt", ["--devices", "0,0", "--split",
                                                                             "sort-last"]),
    "cluster_views2_sort_last": ("cluster_like", "many_lights_odd", ["-p", "views=2", "--devices", "0,0",
                                                                     "--split", "sort-last"]),
}


@vulkan
@pytest.mark.parametrize("case", sorted(RUNS))
def test_runs_clean_under_validation(case: str, capsys) -> None:
    graph, scene, extra = RUNS[case]
    rc, err = _run(capsys, [_g(graph), "--scene", _s(scene), "--size", "20x12", "--frames", "2", "--validate",
                            *extra])
    assert rc == 0, err
    assert "0 validation message(s)" in err and "data check ok" in err


@vulkan
def test_a_wrong_ray_query_fails_the_data_check(capsys, monkeypatch) -> None:
    from rgraph.vk import probe_glsl

    rays = list(probe_glsl.PROBE_RAYS)
    rays[0] = ((9.25, 0.5, -1.0), (0.0, 0.0, 1.0))  # misses instance 0: the miss value instead of value + 1
    monkeypatch.setattr(probe_glsl, "PROBE_RAYS", tuple(rays))
    rc, err = _run(capsys, [_g("rt_ray_query_compute"), "--size", "8x8", "--check-data"])
    assert rc == 1 and "data mismatch: img" in err


TRACE_SCENES = {"rt_refit": "far_world", "rt_persistent_scene_probe_trace": "presets",
                "rt_refit_compute_queue": "deformable_rt"}
RAY_TRACING_GRAPHS = sorted(p.stem for p in GRAPHS if p.stem.startswith("rt_")
                            if p.stem not in {graph for graph, _, _ in RUNS.values()})


@vulkan
@pytest.mark.parametrize("graph", RAY_TRACING_GRAPHS)
def test_ray_tracing_graphs_run_clean_under_validation(graph: str, capsys) -> None:
    """Every other ray tracing fixture: zero validation and syncval messages (under the layer
    setup installs; Debian 12's crashes on ray tracing pipelines), and the probes' data check."""
    scene = TRACE_SCENES.get(graph)
    validate = rt_validates()
    rc, err = _run(capsys, [_g(graph), *(["--scene", _s(scene)] if scene else []), "--size", "12x8",
                            "--frames", "2", "--validate" if validate else "--check-data"])
    assert rc == 0 and ("0 validation message(s)" in err or not validate), err
    assert "data check ok" in err or graph == "rt_spec_example", err  # rt_spec_example: impl passes only


@vulkan
@pytest.mark.parametrize("mode", ["sort-last", "sort-first"])
def test_stereo_split_equals_one_device_in_both_eyes(mode: str) -> None:
    """clustered with views=2 (a layer per eye) over two logical devices: the sort-last composite
    sampled its layered remote images through 2D views (4 validation errors, and wrong pixels in
    both eyes); now one multiview pass composites each eye."""
    import numpy as np
    from multi_helpers import outputs_one_and_split, validated_pair

    pair = validated_pair()
    gpus = next(pair)
    params, size, scene = {"views": "2"}, (64, 48), _s("many_lights_odd")  # the old composite: 23 + 43 px wrong
    _, one, out = outputs_one_and_split(gpus, "clustered", mode, size, scene, params)
    color = np.asarray(one["color"])
    assert color.shape[0] == 2 and not np.array_equal(color[0], color[1])  # two different eyes
    assert np.array_equal(color, np.asarray(out["color"]))
    with pytest.raises(StopIteration):  # closes both devices: no validation message
        next(pair)
