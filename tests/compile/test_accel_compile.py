"""Accel resources in the compiler (FORMAT.md 5): sizes from the build-size query (device or
captured profile), build scratch in the plan, the usage table's accel rows, raytrace stages,
refits of persistent accels, aliasing of transient accels, and errors."""

from __future__ import annotations

import pytest
from locations import TESTS

from rgraph.compiler.pipeline import compile_graph
from rgraph.errors import RGraphError

RT = TESTS / "data" / "rt"


def _res(plan, name):
    return next(r for r in plan["resources"] if r["name"] == name)


def _access(plan, pass_name, resource):
    p = next(p for p in plan["passes"] if p["name"] == pass_name)
    return next(a for a in p["accesses"] if a["resource"] == resource)


def test_accel_sized_by_the_profile_with_scratch_owned_by_the_build_pass():
    plan = compile_graph(RT / "rt_probe.yaml", size=(32, 32))
    accel = _res(plan, "scene_as")
    layout = accel["accel"]
    assert layout["geometry"] == "probe" and layout["tlas"]["instances"] == 2
    assert [b["triangles"] for b in layout["blas"]] == [2]
    # lavapipe's captured sizes: BLAS 104 n - 16 (n >= 2), TLAS 176 n - 16, TLAS at a 256-aligned offset
    assert (layout["blas"][0]["bytes"], layout["tlas"]["bytes"], layout["tlas"]["offset"]) == (192, 336, 256)
    assert accel["bytes"] == accel["size_bytes"] == 256 + 336
    scratch = _res(plan, "scene_as.scratch")
    assert scratch["scratch_of"] == "scene_as" and scratch["usages"] == ["accel_scratch"]
    assert scratch["bytes"] == layout["scratch_bytes"] > 0
    build = next(p for p in plan["passes"] if p["name"] == "build_as")
    assert scratch["first"] == scratch["last"] == build["index"]
    assert _access(plan, "build_as", "scene_as.scratch")["stages"] == ["ACCELERATION_STRUCTURE_BUILD_KHR"]


def test_usage_table_accel_rows_and_raytrace_stages():
    plan = compile_graph(RT / "rt_probe.yaml", size=(32, 32))
    build = _access(plan, "build_as", "scene_as")
    assert (build["stages"], build["access"]) == (["ACCELERATION_STRUCTURE_BUILD_KHR"],
                                                  ["ACCELERATION_STRUCTURE_WRITE_KHR"])
    read = _access(plan, "trace", "scene_as")
    assert (read["stages"], read["access"]) == (["RAY_TRACING_SHADER_KHR"], ["ACCELERATION_STRUCTURE_READ_KHR"])
    for resource in ("gbuf", "params", "color"):
        assert _access(plan, "trace", resource)["stages"] == ["RAY_TRACING_SHADER_KHR"]


def test_persistent_accel_with_deformable_meshes_is_refitted():
    plan = compile_graph(RT / "rt_refit.yaml", size=(32, 32))  # no scene: every feature present
    refit = _access(plan, "refit_as", "scene_as")
    assert refit["access"] == ["ACCELERATION_STRUCTURE_READ_KHR", "ACCELERATION_STRUCTURE_WRITE_KHR"]
    assert _res(plan, "scene_as")["accel"]["refit"] is True
    # trace (frame N) -> refit (frame N+1): a WAR barrier before the refit
    barrier = next(b for b in next(p for p in plan["passes"] if p["name"] == "refit_as")["barriers"]
                   if b["resource"] == "scene_as")
    assert barrier["src"]["stages"] == ["RAY_TRACING_SHADER_KHR"]
    assert barrier["dst"]["stages"] == ["ACCELERATION_STRUCTURE_BUILD_KHR"]


def test_persistent_accel_without_deformable_meshes_is_built_once(tmp_path):
    scene = tmp_path / "still.yaml"
    scene.write_text("scene: 1\nmaterials: {m: {}}\nmeshes:\n  - {shape: box, material: m}\n")
    graph = tmp_path / "g.yaml"
    graph.write_text((RT / "rt_refit.yaml").read_text().replace("requires: [deformable_meshes]", "side_effects: true"))
    plan = compile_graph(graph, scene_path=scene, size=(32, 32))
    layout = _res(plan, "scene_as")["accel"]
    assert layout["refit"] is False and layout["scratch_bytes"] == 0
    assert _access(plan, "refit_as", "scene_as")["access"] == ["ACCELERATION_STRUCTURE_WRITE_KHR"]
    assert not any(r["name"] == "scene_as.scratch" for r in plan["resources"])


def test_transient_accels_alias():
    plan = compile_graph(RT / "rt_rebuild.yaml", size=(32, 32), policy="aliased")
    assert _res(plan, "scene_as")["lifetime"] == "transient"
    scratch = _res(plan, "scene_as.scratch")
    assert scratch["first"] == 0 and scratch["last"] == 2  # both builds


def test_scene_accel_counts_the_scenes_meshes(tmp_path):
    scene = tmp_path / "s.yaml"
    scene.write_text("scene: 1\nmaterials: {m: {}}\nmeshes:\n  - {shape: box, material: m}\n"
                     "  - {shape: sphere, material: m, instances: {grid: [2, 1, 1], spacing: 2}}\n")
    graph = tmp_path / "g.yaml"
    graph.write_text((RT / "rt_probe.yaml").read_text().replace(
        "    writes: {scene_as: accel_build}", "    impl: accel_build\n    writes: {scene_as: accel_build}"))
    plan = compile_graph(graph, scene_path=scene, size=(32, 32))
    layout = _res(plan, "scene_as")["accel"]
    assert layout["geometry"] == "scene"
    assert [b["triangles"] for b in layout["blas"]] == [12, 32 * 16 * 2 - 2 * 32]  # box, sphere 32x16
    assert layout["tlas"]["instances"] == 3


def test_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text((RT / "rt_probe.yaml").read_text().replace("  build_as:\n    kind: compute",
                                                              "  build_as:\n    kind: raster"))
    with pytest.raises(RGraphError) as err:
        compile_graph(bad, size=(32, 32))
    assert "accel_build" in str(err.value) and "raster" in str(err.value)
    profile = tmp_path / "p.json"
    import json

    from rgraph.memory_requirements import PROFILES_DIR

    data = json.loads((PROFILES_DIR / "lavapipe.json").read_text())
    del data["accel"]
    profile.write_text(json.dumps(data))
    with pytest.raises(RGraphError) as err:
        compile_graph(RT / "rt_probe.yaml", size=(32, 32), profile=str(profile))
    assert "no acceleration-structure sizes" in str(err.value)


@pytest.mark.vulkan
def test_profile_sizes_equal_the_live_devices(memory):
    for name in ("rt_probe", "rt_refit", "rt_rebuild"):
        by_profile = compile_graph(RT / f"{name}.yaml", size=(32, 32))
        by_device = compile_graph(RT / f"{name}.yaml", size=(32, 32), memory=memory)
        for a, b in zip(by_profile["resources"], by_device["resources"], strict=True):
            assert (a["name"], a["bytes"], a.get("accel")) == (b["name"], b["bytes"], b.get("accel"))
