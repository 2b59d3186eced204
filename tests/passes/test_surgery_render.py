"""The bundled surgery graph rendered by its real passes on lavapipe, per scene variant.

Each variant drops exactly its effect's passes and their memory, runs with validation and
synchronization validation at zero messages, and produces a finite image; the full scene is
compared with a golden image (tolerance in 8-bit levels; diff images on failure).
"""

from __future__ import annotations

import numpy as np
import pytest
from golden_images import assert_image_close

from rgraph.compiler.pipeline import compile_graph
from rgraph.resources import graphs_dir

SIZE = (96, 54)
PARAMS = {"shadow.size": "256"}  # small shadow maps keep lavapipe fast; the graph's own default is 2048

VARIANTS = {  # scene -> (passes culled, resources freed with them)
    "cct": (set(), set()),
    "cct_no_sss": ({"sss_blur_h", "sss_blur_v"}, {"sss_tmp"}),
    "cct_no_decals": ({"decals"}, set()),  # decals blend into diffuse/specular: no memory of their own
    "cct_no_shadows": ({"shadow"}, {"shadow_maps"}),
}


def render(scene: str, frames: int = 2):
    from rgraph.vk.executor import execute_plan

    plan = compile_graph("surgery", scene_path=graphs_dir() / "scenes" / f"{scene}.yaml", params=PARAMS, size=SIZE)
    return plan, execute_plan(plan, validate=True, frames=frames, read_outputs=True)


@pytest.mark.vulkan
@pytest.mark.parametrize("scene", sorted(VARIANTS))
def test_variant_renders_clean_without_its_effect(scene):
    plan, result = render(scene)
    passes, freed = VARIANTS[scene]
    assert {c["pass"] for c in plan["culled"]} == passes
    assert all(c["reason"].startswith("scene has no") for c in plan["culled"])
    dropped = {r for c in plan["culled"] for r in c["resources"]}
    assert dropped == freed and not dropped & {r["name"] for r in plan["resources"]}
    saved = sum(c["bytes"] or 0 for c in plan["culled"])
    assert (saved > 0) == bool(freed)
    assert all(p.get("impl") for p in plan["passes"]), "every surgery pass runs a real implementation"
    assert [m.text for m in result.messages] == []
    color = result.outputs["color"]
    assert color.shape == (SIZE[1], SIZE[0], 4) and np.isfinite(color).all()
    assert color[..., :3].std() > 0.02, "a real picture, not a flat fill"


@pytest.mark.vulkan
def test_full_scene_matches_its_golden_image():
    _, result = render("cct")
    assert_image_close("surgery_cct_96x54", result.outputs["color"], tolerance=3, max_fraction_over=0.002)
