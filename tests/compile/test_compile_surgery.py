"""The bundled surgery graph: golden plans, determinism, and scene-driven culling."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from locations import TESTS

from rgraph.cli import main
from rgraph.compiler.pipeline import compile_graph
from rgraph.plan import dumps_json as dumps
from rgraph.resources import graphs_dir

GOLDEN = TESTS / "golden"
SCENES = ["cct", "cct_no_sss", "cct_no_decals", "cct_no_shadows"]


def _plan(scene: str) -> dict:
    return compile_graph("surgery", scene_path=graphs_dir() / "scenes" / f"{scene}.yaml", size=(320, 180))


@pytest.mark.parametrize("scene", SCENES)
def test_golden_plan(scene: str) -> None:
    """Plans are byte-identical to the checked-in golden files (RGRAPH_UPDATE_GOLDEN=1 rewrites them)."""
    text = dumps(_plan(scene)).replace(str(graphs_dir()), "<graphs>")
    golden = GOLDEN / f"surgery_{scene}.json"
    if os.environ.get("RGRAPH_UPDATE_GOLDEN"):
        golden.parent.mkdir(exist_ok=True)
        golden.write_text(text)
    assert golden.exists(), f"missing {golden}; run with RGRAPH_UPDATE_GOLDEN=1"
    assert text == golden.read_text()


def test_compile_is_deterministic(tmp_path: Path) -> None:
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert main(["compile", "surgery", "--size", "320x180", "-o", str(a)]) == 0
    assert main(["compile", "surgery", "--size", "320x180", "-o", str(b)]) == 0
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize(
    "scene,dropped,reason",
    [
        ("cct_no_sss", {"sss_blur_h", "sss_blur_v"}, "scene has no sss_materials"),
        ("cct_no_decals", {"decals"}, "scene has no decals"),
        ("cct_no_shadows", {"shadow"}, "scene has no shadow_lights"),
    ],
)
def test_variant_scene_drops_passes_and_memory(scene: str, dropped: set[str], reason: str) -> None:
    full, plan = _plan("cct"), _plan(scene)
    culled = {c["pass"]: c for c in plan["culled"]}
    assert set(culled) == dropped
    assert all(c["reason"] == reason for c in culled.values())
    names = {p["name"] for p in plan["passes"]}
    assert not names & dropped
    saved = full["stats"]["unaliased_bytes"] - plan["stats"]["unaliased_bytes"]
    only_theirs = sorted({r for c in culled.values() for r in c["resources"]})
    assert (saved > 0) == bool(only_theirs)  # decals use no memory of their own
    if scene == "cct_no_shadows":
        assert culled["shadow"]["resources"] == ["shadow_maps"]
        assert "shadow_maps" not in {r["name"] for r in plan["resources"]}
        forward = next(p for p in plan["passes"] if p["name"] == "forward")
        assert "shadow_maps" not in {a["resource"] for a in forward["accesses"]}
        assert {"pass": "forward", "resource": "shadow_maps"}.items() <= plan["dropped_reads"][0].items()


def test_default_scene_is_the_graphs_own() -> None:
    plan = compile_graph("surgery", size=(320, 180))
    assert plan["scene"] == "cct"
    assert json.loads(dumps(plan)) == plan
