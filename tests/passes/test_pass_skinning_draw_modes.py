"""Skinned characters in every draw mode (issue 18: skinning x GPU-driven drawing) on lavapipe
under validation + synchronization validation (zero messages).

graphs/clustered.yaml draws the two-character scene of tests/skinning_helpers.py with
draw.mode cpu, gpu (persistent Instance table, draw_cull, one vkCmdDrawIndexedIndirectCount:
the skinned flag, bone stride and first bone entry travel in Instance.info, the vertex base is
the TLSF placement), gpu with float32 hi/lo translations, and naive (per-object CPU culling,
one indirect draw per object), mono and views=2. In each mode and eye the raster passes pose
like the float64 reference (passes/skinning_ref.py) of the same half-float logic states:

- the drawn silhouette equals the posed reference mesh's, rasterised in NumPy at pixel centres
  (at most 3 edge pixels apart), while the rest pose's differs in many - an unposed draw fails;
- the nearest depth is the nearest posed vertex's;
- forward's depth_read test passes on exactly the prepass's pixels (both vertex shaders pose
  identically);
- the depth image equals draw.mode=cpu's within float rounding.
"""

from __future__ import annotations

import numpy as np
import pytest
from skinning_helpers import clip_of, reference_pose, run_skinned

from rgraph.scene.instances import eye_view_projs

IPD = 0.3  # wide eyes: the two views differ clearly
SIZE = (96, 72)
CASES = [("cpu", 1, {}), ("gpu", 1, {}), ("gpu", 1, {"draw.float64": "false"}), ("naive", 1, {}),
         ("gpu", 2, {}), ("naive", 2, {})]


def _render(tmp_path, mode: str, views: int, extra: dict):
    params = {"draw.mode": mode, "views": str(views), "views.ipd": str(IPD), **extra}
    data, mesh, out = run_skinned(tmp_path, readback=False, outputs=("depth", "hdr"), floor=False, params=params,
                                   size=SIZE)
    w, h = SIZE
    return data, mesh, out["depth"].reshape(views, h, w), out["hdr"].reshape(views, h, w, -1)[..., :3]


def _ndc(world: np.ndarray, view_proj) -> np.ndarray:
    clip = clip_of(world, view_proj)
    return clip[..., :3] / clip[..., 3:4]


def _coverage(world: np.ndarray, triangles: np.ndarray, view_proj) -> np.ndarray:
    """(h, w) pixels whose centre lies in some triangle of the camera-relative ``world``
    (instances, V, 3) vertices, either winding: the silhouette a closed mesh covers with any
    face culling (float64, edges inclusive)."""
    w, h = SIZE
    out = np.zeros((h, w), dtype=bool)
    for instance in world:
        ndc = _ndc(instance, view_proj)
        px, py = (ndc[:, 0] + 1) * 0.5 * w, (ndc[:, 1] + 1) * 0.5 * h
        for tri in triangles:
            xs, ys = px[tri], py[tri]
            x0, x1 = max(int(np.floor(xs.min() - 0.5)), 0), min(int(np.ceil(xs.max() - 0.5)), w - 1)
            y0, y1 = max(int(np.floor(ys.min() - 0.5)), 0), min(int(np.ceil(ys.max() - 0.5)), h - 1)
            if x0 > x1 or y0 > y1:
                continue
            gx, gy = np.meshgrid(np.arange(x0, x1 + 1) + 0.5, np.arange(y0, y1 + 1) + 0.5)
            e = [(xs[(k + 1) % 3] - xs[k]) * (gy - ys[k]) - (ys[(k + 1) % 3] - ys[k]) * (gx - xs[k]) for k in range(3)]
            out[y0:y1 + 1, x0:x1 + 1] |= (((e[0] >= 0) & (e[1] >= 0) & (e[2] >= 0))
                                          | ((e[0] <= 0) & (e[1] <= 0) & (e[2] <= 0)))
    return out


@pytest.mark.vulkan
@pytest.mark.parametrize(("mode", "views", "extra"), CASES,
                         ids=[f"{m}-views{v}{'-f32' if e else ''}" for m, v, e in CASES])
def test_every_draw_mode_poses_skinned_characters_like_the_reference(tmp_path, mode, views, extra):
    data, mesh, depth, hdr = _render(tmp_path, mode, views, extra)
    cam = data.camera(0)
    offset = mesh.positions[:, None, :] - cam.position
    posed = reference_pose(mesh, 0, None)[0] + offset
    rest = mesh.data.positions[None, :, :] + offset
    projs = eye_view_projs(data, 0, views, IPD) if views > 1 else [cam.view_proj]
    for eye, vp in enumerate(projs):
        covered = depth[eye] > 0
        assert covered.sum() > 0.03 * covered.size, f"eye {eye}: nothing drawn"
        assert np.array_equal(hdr[eye].astype(np.float64).sum(axis=-1) > 0, covered), f"eye {eye}: depth holes"
        triangles = mesh.data.indices.reshape(-1, 3)
        wrong = int((_coverage(posed, triangles, vp) != covered).sum())
        assert wrong <= 3, f"eye {eye}: {wrong} pixels differ from the posed reference's silhouette"
        unposed = int((_coverage(rest, triangles, vp) != covered).sum())
        assert unposed > 40, f"eye {eye}: the rest pose differs in only {unposed} pixels (no teeth)"
        nearest = _ndc(posed, vp)[..., 2].max()
        assert nearest * 0.97 < depth[eye].max() <= nearest * 1.0001, eye
    if views > 1:
        assert (depth[0] != depth[1]).sum() > 20  # each eye its own view


@pytest.mark.vulkan
def test_gpu_and_naive_depth_equal_cpu_depth(tmp_path):
    images = {mode: _render(tmp_path, mode, 1, {})[2][0] for mode in ("cpu", "gpu", "naive")}
    for mode in ("gpu", "naive"):
        diff = np.abs(images[mode].astype(np.float64) - images["cpu"])
        assert (images[mode] > 0).sum() == (images["cpu"] > 0).sum(), mode
        assert diff.max() < 1e-5 * images["cpu"].max(), f"{mode}: max depth diff {diff.max()}"
