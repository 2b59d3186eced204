"""shaders/scene/shadow.glsl (shadow_pcf) on lavapipe vs passes/scene_ref.shadow_pcf_reference.

A test-only compute pass evaluates shadow_pcf for both layers at every visible pixel (world
position from the prepass depth through scene_world_from_depth); NumPy does the same in
float64 on the read-back maps. Tolerance: at most 3% of the pixels may differ by more than
one tap (points within float32 noise of a stored depth or of a texel edge), none by more
than half the taps.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rgraph.passes import scene_ref

from rgraph.compiler.pipeline import compile_graph
from rgraph.impl import PassImpl, register
from rgraph.scene.build import load_scene_data
from rgraph.vk.passkit import Binding, pack

GRAPH = TESTS / "pass_graphs" / "scene_shadow_probe.yaml"
SCENE = TESTS / "pass_graphs" / "scene_simple_scene.yaml"


@register("test_scene_shadow_probe")
class ShadowProbe(PassImpl):
    def __init__(self, setup):
        super().__init__(setup)
        self.scene = setup.scene
        self.taps = int(setup.param("shadow.pcf_taps", 9))
        self.sets = setup.descriptors([Binding(0, "sampled", "depth", sampler="nearest"),
                                       Binding(1, "sampled", "shadow_maps", array=True, sampler="nearest"),
                                       Binding(2, "storage_image", "lit")])
        self.pipeline = setup.compute_pipeline("scene/tests/shadow_probe.comp", [self.scene.set_layout, self.sets.layout],
                                               push_constant_bytes=16)
        self.extent = setup.extent_of("lit")

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, pack("4i", self.taps, 0, 0, 0))
        rec.dispatch(-(-self.extent[0] // 8), -(-self.extent[1] // 8))


@pytest.mark.vulkan
@pytest.mark.parametrize("taps", [1, 9, 16])
def test_shadow_pcf_matches_reference(taps):
    from rgraph.vk.executor import execute_plan

    w, h = 48, 32
    plan = compile_graph(GRAPH, size=(w, h), params={"shadow.pcf_taps": str(taps)})
    result = execute_plan(plan, validate=True, frames=1, read_outputs=True)
    assert [m.text for m in result.messages] == []
    lit, depth, maps = result.outputs["lit"], result.outputs["depth"][..., 0], result.outputs["shadow_maps"]
    assert np.isfinite(lit).all()
    scene = load_scene_data(SCENE, (w, h))
    cam = scene.camera(0)
    ys, xs = np.nonzero(depth > 0)
    ndc = np.stack([(xs + 0.5) / w * 2 - 1, (ys + 0.5) / h * 2 - 1, depth[ys, xs], np.ones(len(xs))], axis=1)
    world = ndc @ np.linalg.inv(cam.view_proj).T
    world = world[:, :3] / world[:, 3:]
    n = max(1, round(taps ** 0.5))
    for layer, matrix in enumerate(scene.shadow_matrices(cam.position)):
        want = scene_ref.shadow_pcf_reference(maps[layer, ..., 0].astype(np.float64), matrix, world, taps)
        got = lit[ys, xs, layer]
        diff = np.abs(got - want)
        assert (diff > 1.0 / (n * n) + 1e-6).mean() <= 0.03
        assert diff.max() <= 0.5 + 1e-6
        assert 0.05 < want.mean() < 0.999  # some of the scene is in shadow, most of it lit
    assert np.all(lit[depth <= 0] == -1)
