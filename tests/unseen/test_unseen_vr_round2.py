"""Issue 18's scenes (instanced, unique, skinned; clustered.yaml, stereo, --naive-cpu, --logic-hz)
with inputs written from FORMAT.md 7 by a hostile user, second round (tests/fixtures/unseen/bad/
vr_scenes and scenes/). Each bug these inputs found stays fixed:

- scene values of the wrong type were coerced silently (``unique: "yes"``, ``deformable: "no"``,
  ``count: true``, ``position: ["1", ...]``, ``grid: [2, 2.0, 2]``): scene models are strict now,
  like the graph's, and each is a located error;
- a worktree run with ``PYTHONPATH`` (the README's way to run a checkout) took its graphs,
  shaders and pass implementations from whichever checkout an editable install maps
  ``rgraph.<name>`` to: a fix to a shader or a pass was never run. A checkout's own data wins;
- draw_cull and light_setup dispatched one workgroup row: past 65,535 groups (17 meshes at the
  per-mesh instance limit, five light generators at theirs) the dispatch was invalid;
- ``--naive-cpu`` on a graph without ``draw.mode`` (surgery, async_overlap) said "unknown param
  'draw.mode'" (a param the user never gave), and on a plan file "-p only applies ...";
- 730,000 instances (under the per-mesh limit) made a 140 MB instance table, bound past the
  device's maxStorageBufferRange (128 MiB on lavapipe): two validation errors, undefined reads
  without the layer. It is refused before binding, with the size, the limit and what fits.
"""

from __future__ import annotations

import importlib.util
from importlib.machinery import ModuleSpec
from pathlib import Path

import pytest
from locations import ROOT, TESTS
from test_unseen_inputs import _diagnostics

vulkan = pytest.mark.vulkan
BAD = TESTS / "fixtures" / "unseen" / "bad" / "vr_scenes"
SCENES = TESTS / "fixtures" / "unseen" / "scenes"


def test_wrong_types_in_scene_values_are_located_errors(capsys) -> None:
    path = str(BAD / "wrong_types.yaml")
    rc, diags = _diagnostics(capsys, ["validate", "clustered", "--scene", path])
    assert rc == 2
    got = [(d["file"], d["line"], d["col"], d["message"]) for d in diags]
    assert got == [
        (path, 6, 57, "expected true or false for 'shadows', got string 'true'"),
        (path, 9, 39, "expected true or false for 'unique', got string 'yes'"),
        (path, 10, 43, "expected true or false for 'deformable', got string 'no'"),
        (path, 11, 50, "expected an integer for 'count', got boolean true"),
        (path, 12, 42, "expected a number for 'position', got string '1'"),
        (path, 13, 53, "expected an integer for 'grid', got number 2.0"),
    ]


def test_a_checkout_uses_its_own_shaders_graphs_and_passes(tmp_path: Path, monkeypatch) -> None:
    from rgraph import resources

    other = tmp_path / "other_checkout"  # what an editable install of another worktree maps to
    real = importlib.util.find_spec

    def mapped(name: str, *args):
        if name.startswith("rgraph.") and name.count(".") == 1:
            spec = ModuleSpec(name, None, is_package=True)
            spec.submodule_search_locations = [str(other / name.split(".")[1])]
            return spec
        return real(name, *args)

    monkeypatch.setattr(importlib.util, "find_spec", mapped)
    for name in ("graphs", "shaders", "passes"):
        assert resources.data_dir(name) == ROOT / name
    assert Path(resources.builtin_passes().__file__).parent == ROOT / "passes"
    from rgraph.vk.shaders import shader_dirs

    assert shader_dirs()[-1] == ROOT / "shaders"


def test_dispatch_groups_fold_into_rows_within_the_device_minimum() -> None:
    from rgraph.vk.dispatch import MAX_GROUPS_X, groups_2d

    assert groups_2d(0, 256) == (1, 1) and groups_2d(256, 256) == (1, 1) and groups_2d(257, 256) == (2, 1)
    # 17 meshes of the 1,048,576-instance limit: 69,633 groups of 256, over 65,535 in one dimension
    x, y = groups_2d(17 << 20, 256)
    assert (x, y) == (MAX_GROUPS_X, 2) and x * y * 256 >= 17 << 20
    assert groups_2d(5 << 20, 64) == (MAX_GROUPS_X, 2)  # five 1,048,576-light generators
    with pytest.raises(ValueError):
        groups_2d(MAX_GROUPS_X * MAX_GROUPS_X * 64 + 1, 64)


@pytest.mark.vulkan
@pytest.mark.parametrize("order", ["none", "front_to_back"])
def test_culling_and_light_setup_in_rows_of_groups_equal_one_row(tmp_path: Path, monkeypatch, order: str) -> None:
    """draw_cull and light_setup dispatched ``(count / group, 1, 1)``: past 65,535 groups (16.7 M
    instances, 4.2 M lights) the dispatch is invalid and the rest is never culled or lit. Rows of
    two groups here (1,129 instances: 5 cull groups; 301 lights: 5 light groups) give the same
    draws and image as one row."""
    import numpy as np
    from clustered_helpers import graph_with_outputs, render

    from rgraph.vk import dispatch

    scene = SCENES / "many_groups.yaml"
    graph = graph_with_outputs(tmp_path, ("draw_args",))
    params = {"draw.order": order}
    _, one = render(scene, size=(48, 32), graph=graph, params=params)
    monkeypatch.setattr(dispatch, "MAX_GROUPS_X", 2)
    _, rows = render(scene, size=(48, 32), graph=graph, params=params)
    counts = [int(np.frombuffer(bytes(o["draw_args"]), dtype=np.uint32)[0]) for o in (one, rows)]
    assert counts[0] > 256 and counts[0] == counts[1]
    assert np.array_equal(np.asarray(one["color"]), np.asarray(rows["color"]))


@pytest.mark.parametrize("target, message", [
    ("surgery", "--naive-cpu needs a graph with param 'draw.mode' (graphs/clustered.yaml); surgery has none"),
    ("async_overlap", "--naive-cpu needs a graph with param 'draw.mode' (graphs/clustered.yaml); async_overlap "
                      "has none"),
    ("plan", "--naive-cpu (-p draw.mode=naive) only applies when compiling a graph, not to a plan file"),
])
def test_naive_cpu_on_a_graph_without_draw_modes_names_the_flag(target: str, message: str, tmp_path: Path,
                                                                  capsys) -> None:
    from rgraph.cli import main

    if target == "plan":
        target = str(tmp_path / "plan.json")
        assert main(["compile", "clustered", "--size", "16x8", "-o", target]) == 0
    rc, diags = _diagnostics(capsys, ["run", target, "--naive-cpu"])
    assert rc == 2 and [(d["file"], d["message"]) for d in diags] == [("<command line>", message)]


@vulkan
def test_an_instance_table_over_the_storage_range_is_refused_not_bound(capsys) -> None:
    from rgraph.cli import main

    capsys.readouterr()
    rc = main(["run", "clustered", "--scene", str(BAD / "over_storage_range.yaml"), "--size", "8x8", "--validate"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err and "validation message" not in err, err
    assert ("the scene's instance (draw) table is 140,160,000 bytes (730,000 draws), over this device's "
            "maxStorageBufferRange of 134,217,728 bytes: use fewer instances or lights (about 699,050 draws fit)") in err
