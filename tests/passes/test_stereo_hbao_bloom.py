"""Stereo (graph param ``views`` = 2) HBAO chain and bloom chain on lavapipe: a layer per eye.

Oracle: the views=2 run of a chain on 2-layer inputs must give, on output layer k, exactly
what the bundled mono test graph (``hbao.yaml``, ``bloom_chain.yaml``; views=1, unchanged
shaders) gives on input layer k alone, for k = 0, 1. Exact equality, no tolerance: the
stereo shaders run the same arithmetic on the same texels (only the image dimensionality and
the dispatch / instance z differ), and lavapipe is deterministic. The inputs' layers differ
(two eyes' depth, two HDR images), and so must the outputs' layers, so a pass that reads or
writes the wrong layer (e.g. always layer 0) fails. Validation and synchronization
validation are on; no message is allowed.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rgraph.passes.screenspace_ref import Camera, render_depth

GRAPHS = TESTS / "pass_graphs"
W, H = 48, 32
FOV, NEAR, IPD = 50.0, 0.05, 0.064


def run(graph: str, inputs: dict[str, np.ndarray], params: dict | None = None) -> dict[str, np.ndarray]:
    """One frame of ``pass_graphs/<graph>`` at W x H under validation; outputs as float32
    (layers, h, w, c) or (h, w, c)."""
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / graph, size=(W, H), params={k: str(v) for k, v in (params or {}).items()})
    result = execute_plan(plan, validate=True, frames=1, inputs=inputs, read_outputs=True)
    assert [m.text for m in result.messages] == []
    return {k: np.asarray(v) for k, v in result.outputs.items()}


def eye_depth(eye: float) -> np.ndarray:
    """Reversed-Z depth (h, w, 1) of a corner (floor, back wall, right wall, sphere, box) seen
    from ``eye`` metres along the camera's x axis, with a sky cut-out: a stereo pair."""
    cam = Camera(fov_y=FOV, near=NEAR, aspect=W / H)
    shift = np.array([-eye, 0.0, 0.0])  # view space of the eye: the scene moves the other way
    at = lambda p: tuple(np.asarray(p, float) + shift)  # noqa: E731
    d = render_depth(W, H, cam, planes=[(at((0, -0.4, 0)), (0, 1, 0)), (at((0, 0, -1.8)), (0, 0, 1)),
                                        (at((0.7, 0, 0)), (-1, 0, 0))],
                     spheres=[(at((0.15, -0.2, -1.3)), 0.2)],
                     boxes=[(at((-0.6, -0.4, -1.5)), at((-0.3, -0.1, -1.2)))])
    d[: H // 5, : (2 * W) // 5] = 0.0
    return d.astype(np.float32)[..., None]


def hdr_image(seed: int) -> np.ndarray:
    """Half-float radiance (h, w, 4): a dim background and bright blobs above the threshold."""
    rng = np.random.default_rng(seed)
    hdr = np.ones((H, W, 4))
    hdr[..., :3] = rng.uniform(0.0, 0.9, (H, W, 3))
    yy, xx = np.mgrid[0:H, 0:W]
    for _ in range(3):
        cy, cx, peak = rng.uniform(0, H), rng.uniform(0, W), rng.uniform(2.5, 20.0)
        hdr[..., :3] += peak * np.exp(-((yy - cy) ** 2 + (xx - cx) ** 2) / 12.0)[..., None] * rng.uniform(0.5, 1, 3)
    return hdr.astype(np.float16).astype(np.float32)


def assert_layers_are_mono_runs(stereo: dict, mono: list[dict], names: tuple[str, ...]) -> None:
    for name in names:
        assert stereo[name].shape == (2, *mono[0][name].shape), name
        for k in (0, 1):
            np.testing.assert_array_equal(stereo[name][k], mono[k][name], err_msg=f"{name} layer {k}")
        assert not np.array_equal(stereo[name][0], stereo[name][1]), f"{name}: the eyes' layers are equal"


@pytest.mark.vulkan
def test_stereo_hbao_layers_equal_mono_runs_on_each_eye():
    eyes = [eye_depth(-IPD / 2), eye_depth(IPD / 2)]
    assert not np.array_equal(eyes[0], eyes[1])
    knobs = {"hbao.radius": 0.6, "hbao.strength": 1.5}
    stereo = run("stereo_hbao.yaml", {"depth": np.stack(eyes)}, {"views": 2, **knobs})
    mono = [run("hbao.yaml", {"depth": e}, knobs) for e in eyes]
    assert_layers_are_mono_runs(stereo, mono, ("depth_quarter", "ao_quarter", "ao"))
    for k in (0, 1):  # not vacuous: real occlusion and sky in each eye
        assert stereo["ao"][k].min() < 0.8 and (stereo["ao"][k][eyes[k] == 0] == 1.0).all()


@pytest.mark.vulkan
def test_stereo_bloom_layers_equal_mono_runs_on_each_eye():
    eyes = [hdr_image(1), hdr_image(2)]
    knobs = {"bloom.intensity": 0.5}  # a visible bloom in the combined hdr
    stereo = run("stereo_bloom.yaml", {"hdr": np.stack(eyes)}, {"views": 2, **knobs})
    mono = [run("bloom_chain.yaml", {"hdr": e}, knobs) for e in eyes]
    assert_layers_are_mono_runs(stereo, mono, ("bloom_a", "bloom_b", "hdr"))
    for k in (0, 1):  # not vacuous: the bright pass keeps something and the combine adds it
        assert (stereo["bloom_a"][k][..., :3] > 0).any()
        assert (stereo["hdr"][k][..., :3] > eyes[k][..., :3]).any()


@pytest.mark.vulkan
def test_views_2_with_an_image_of_one_layer_is_a_clear_error():
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / "stereo_bloom_unlayered.yaml", size=(W, H))
    with pytest.raises(ExecutionError, match=r"views=2 needs bloom_a with a layer per view .*it has 1"):
        execute_plan(plan, validate=True, inputs={"hdr": np.stack([hdr_image(1), hdr_image(2)])})


@pytest.mark.vulkan
def test_stereo_hbao_after_a_multiview_depth_prepass_equals_mono_hbao_on_each_eye():
    """The graph-level path: a multiview depth prepass over a scene (where the scene's shader
    defines carry RGRAPH_VIEWS too) on the graphics queue, HBAO on the async compute queue."""
    stereo = run("stereo_scene_hbao.yaml", {}, {"views": 2})
    depth = stereo["depth"]
    assert depth.shape == (2, H, W, 1) and not np.array_equal(depth[0], depth[1])
    knobs = {"hbao.radius": 0.6, "hbao.strength": 1.5}
    mono = [run("hbao.yaml", {"depth": depth[k]}, knobs) for k in (0, 1)]
    assert_layers_are_mono_runs(stereo, mono, ("ao",))
    assert stereo["ao"][0].min() < 0.9 and stereo["ao"][1].min() < 0.9  # some occlusion in each eye
