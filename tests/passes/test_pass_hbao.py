"""HBAO passes (hbao_downsample, hbao, hbao_upsample) against their NumPy float64 references.

Tolerances: ``depth_quarter`` exact (a max of float32 values); ``ao_quarter`` within 2/255
of the reference run on the GPU's own ``depth_quarter`` (r8 rounding plus float32 vs
float64 trigonometry); ``ao`` within 2/255 of the reference upsample of the GPU's own
``ao_quarter``. Each stage is checked on its actual input so errors do not compound.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import TESTS
from rgraph.passes import hbao_ref as ref
from rgraph.passes.screenspace_ref import Camera, render_depth

from rgraph.compiler.pipeline import compile_graph

GRAPHS = TESTS / "pass_graphs"
FOV, NEAR = 50.0, 0.05
AO_TOL = 2.0 / 255.0


def camera(w: int, h: int) -> Camera:
    return Camera(fov_y=FOV, near=NEAR, aspect=w / h)


def corner_scene(w: int, h: int, sky: bool = True) -> np.ndarray:
    """A floor, two walls, a sphere and a box (view space), with a sky cut-out: reversed-Z depth."""
    d = render_depth(w, h, camera(w, h),
                     planes=[((0, -0.4, 0), (0, 1, 0)), ((0, 0, -1.8), (0, 0, 1)), ((0.7, 0, 0), (-1, 0, 0))],
                     spheres=[((0.15, -0.2, -1.3), 0.2)], boxes=[((-0.6, -0.4, -1.5), (-0.3, -0.1, -1.2))])
    if sky:
        d[: h // 5, : (2 * w) // 5] = 0.0
    return d.astype(np.float32).astype(np.float64)


def run(graph: str, size: tuple[int, int], inputs: dict, params: dict | None = None):
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / graph, size=size, params={k: str(v) for k, v in (params or {}).items()})
    result = execute_plan(plan, validate=True, inputs={k: np.asarray(v, np.float32)[..., None] for k, v in inputs.items()},
                          read_outputs=True)
    assert [m.text for m in result.messages] == []
    for name, arr in result.outputs.items():
        assert np.all(np.isfinite(arr)), f"{name} has NaN/Inf"
    return {k: np.asarray(v, np.float64)[..., 0] for k, v in result.outputs.items()}


# ----------------------------------------------------------------------------- NumPy only


def test_downsample_keeps_the_nearest_surface_of_each_block():
    d = np.zeros((8, 12))
    d[1, 2] = 0.3     # one geometry pixel in an otherwise sky block: the block is geometry
    d[5, 5], d[6, 6] = 0.2, 0.7   # nearest = largest reversed-Z value
    d[4:8, 8:12] = 0.1
    q = ref.downsample(d, (3, 2))
    np.testing.assert_array_equal(q, [[0.3, 0.0, 0.0], [0.0, 0.7, 0.1]])


def test_flat_surfaces_are_unoccluded():
    w, h = 64, 48
    cam = camera(w, h)
    for plane in [((0, -0.4, 0), (0, 1, 0)), ((0, 0, -2), (0.3, 0.2, 1)), ((0, 0, -1), (0, 0, 1))]:
        dq = ref.downsample(render_depth(w, h, cam, planes=[plane]), (16, 12))
        np.testing.assert_allclose(ref.hbao(dq, cam, ref.HBAOSettings(radius=0.5)), 1.0)


def test_a_concave_corner_is_occluded_and_sky_is_not():
    w, h = 96, 64
    cam = camera(w, h)
    d = corner_scene(w, h)
    out = ref.reference(d, cam, ref.HBAOSettings(radius=0.6, strength=1.5))
    assert out["ao"].min() < 0.7 and np.mean(out["ao"] < 0.9) > 0.1
    assert np.all(out["ao"][d == 0] == 1.0)


def test_bilateral_upsample_keeps_depth_edges_that_bilinear_blurs():
    ao_q, dq, d = edge_inputs(32, 16)
    cam = camera(32, 16)
    bil = ref.upsample(ao_q, dq, d, cam, 32.0)
    lin = ref.bilinear_upsample(ao_q, (32, 16))
    np.testing.assert_allclose(bil[:, :16], 64 / 255, atol=1e-6)
    np.testing.assert_allclose(bil[:, 16:], 1.0, atol=1e-6)
    assert np.all(np.abs(lin[:, 14:18] - np.where(np.arange(14, 18) < 16, 0.25, 1.0)) > 0.05)


def edge_inputs(w: int, h: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An AO edge on a depth discontinuity at x = w/2 (a quarter-block boundary)."""
    zf = np.where(np.arange(w) < w // 2, 1.0, 2.0)[None].repeat(h, 0)
    d = NEAR / zf
    qw, qh = w // 4, h // 4
    dq = NEAR / np.where(np.arange(qw) < qw // 2, 1.0, 2.0)[None].repeat(qh, 0)
    ao_q = np.where(np.arange(qw) < qw // 2, 0.25, 1.0)[None].repeat(qh, 0)
    return np.round(ao_q * 255) / 255, dq.astype(np.float32).astype(np.float64), d.astype(np.float32).astype(np.float64)


# ----------------------------------------------------------------------------- lavapipe


@pytest.mark.vulkan
@pytest.mark.parametrize("size,directions,steps", [((96, 64), 8, 4), ((90, 62), 4, 3)])
def test_hbao_chain_matches_reference(size, directions, steps):
    w, h = size
    cam = camera(w, h)
    d = corner_scene(w, h)
    settings = ref.HBAOSettings(directions=directions, steps=steps, radius=0.6, strength=1.5)
    out = run("hbao.yaml", size, {"depth": d}, {"hbao.directions": directions, "hbao.steps": steps,
                                               "hbao.radius": 0.6, "hbao.strength": 1.5})
    dq = out["depth_quarter"]
    np.testing.assert_array_equal(dq, ref.downsample(d, (dq.shape[1], dq.shape[0])))
    want_q = ref.hbao(dq, cam, settings)
    assert np.abs(out["ao_quarter"] - want_q).max() <= AO_TOL
    assert want_q.min() < 0.8  # the scene really has occlusion
    want = ref.upsample(out["ao_quarter"], dq, d, cam, settings.upsample_sharpness)
    assert np.abs(out["ao"] - want).max() <= AO_TOL
    assert np.all(out["ao"][d == 0] == 1.0)  # sky: no occlusion


@pytest.mark.vulkan
def test_sky_never_occludes_on_gpu():
    """A box in front of a wall occludes the wall; the same pixels as sky (depth 0) do not."""
    w, h = 64, 48
    cam = camera(w, h)
    wall = render_depth(w, h, cam, planes=[((0, 0, -1.5), (0, 0, 1))])
    with_box = render_depth(w, h, cam, planes=[((0, 0, -1.5), (0, 0, 1))], boxes=[((-0.2, -0.2, -1.45), (0.2, 0.2, -1.3))])
    box = with_box > wall
    params = {"hbao.radius": 0.6}
    occluded = run("hbao.yaml", (w, h), {"depth": with_box}, params)["ao"]
    assert occluded[~box].min() < 0.9
    holes = np.where(box, 0.0, wall)
    clear = run("hbao.yaml", (w, h), {"depth": holes}, params)
    assert np.all(clear["ao"] == 1.0) and np.all(clear["ao_quarter"] == 1.0)


@pytest.mark.vulkan
def test_upsample_edge_stays_sharp_on_gpu():
    w, h = 32, 16
    ao_q, dq, d = edge_inputs(w, h)
    out = run("hbao_upsample.yaml", (w, h), {"depth": d, "depth_quarter": dq, "ao_quarter": ao_q})["ao"]
    want = ref.upsample(ao_q, dq, d, camera(w, h), 32.0)
    assert np.abs(out - want).max() <= AO_TOL
    assert np.abs(out[:, :16] - 64 / 255).max() <= 1 / 255 and np.all(out[:, 16:] == 1.0)
    lin = ref.bilinear_upsample(ao_q, (w, h))
    assert np.abs(out - lin)[:, 14:18].min() > 0.05  # where a plain bilinear upsample would blur


# ----------------------------------------------------------------------------- hbao.scale


def test_reduction_factor_accepts_only_integer_reciprocals():
    assert [ref.reduction_factor(s) for s in (1, 0.5, 0.25, 1 / 3)] == [1, 2, 4, 3]
    for bad in (0.3, 0.0, 1.5, -0.25):
        with pytest.raises(ValueError, match="hbao.scale"):
            ref.reduction_factor(bad)


def test_downsample_at_factor_1_is_a_copy_and_upsample_the_identity():
    w, h = 24, 16
    cam = camera(w, h)
    d = corner_scene(w, h)
    out = ref.reference(d, cam, ref.HBAOSettings(scale=1.0, radius=0.6, directions=4, steps=3))
    np.testing.assert_array_equal(out["depth_quarter"], d)
    np.testing.assert_allclose(out["ao"], out["ao_quarter"], atol=1e-12)


@pytest.mark.vulkan
@pytest.mark.parametrize("size,scale", [((40, 30), 1.0), ((66, 46), 0.5)])
def test_hbao_chain_at_factor_1_and_2_matches_reference(size, scale):
    """Full resolution (the sweep's reference) and half resolution through the same three passes."""
    w, h = size
    cam = camera(w, h)
    d = corner_scene(w, h)
    settings = ref.HBAOSettings(directions=6, steps=5, radius=0.6, strength=1.5, scale=scale)
    out = run("hbao.yaml", size, {"depth": d}, {"hbao.directions": 6, "hbao.steps": 5, "hbao.radius": 0.6,
                                               "hbao.strength": 1.5, "hbao.scale": scale})
    dq = out["depth_quarter"]
    assert dq.shape == (int(h * scale), int(w * scale))
    np.testing.assert_array_equal(dq, ref.downsample(d, (dq.shape[1], dq.shape[0]), settings.factor))
    want_q = ref.hbao(dq, cam, settings)
    assert np.abs(out["ao_quarter"] - want_q).max() <= AO_TOL
    assert want_q.min() < 0.8
    want = ref.upsample(out["ao_quarter"], dq, d, cam, settings.upsample_sharpness)
    assert np.abs(out["ao"] - want).max() <= AO_TOL
    if scale == 1.0:  # a copy and the identity, bit for bit
        np.testing.assert_array_equal(dq, d)
        np.testing.assert_array_equal(out["ao"], out["ao_quarter"])


@pytest.mark.vulkan
def test_working_size_that_disagrees_with_hbao_scale_is_an_error():
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPHS / "hbao_fixed_size.yaml", size=(32, 16), params={"hbao.scale": "0.5"})
    with pytest.raises(Exception, match=r"depth_quarter is \(8, 4\) but hbao.scale=0.5 gives \(16, 8\)"):
        execute_plan(plan, validate=False, inputs={"depth": np.ones((16, 32, 1), np.float32),
                                                   "depth_quarter": np.ones((4, 8, 1), np.float32),
                                                   "ao_quarter": np.ones((4, 8, 1), np.float32)})
