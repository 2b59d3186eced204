"""The deformable vertices' compute pass (rgraph.vk.scene_deform) against the float64 reference
(rgraph.scene.smoothing), on lavapipe under validation + synchronization validation.

One DeformGPU holds four meshes at once (so vertex, triangle and group offsets between parts
are exercised): the cct neck split at its UV seam, a sphere with hard cases (zero-area
triangles, collapsed vertices, an isolated vertex, a collinear sliver), and a sphere at
1e30 and at 1e-30 scale. The reference is evaluated on the float32 positions the GPU reads.
"""

from __future__ import annotations

import numpy as np
import pytest

import rgraph
from rgraph.scene.deform import Deformer
from rgraph.scene.shapes import MeshData, make_shape, vertex_normals
from rgraph.scene.smoothing import build_topology, normals_tangents
from rgraph.vk.device_local import DeviceLocal, one_time_submitter
from rgraph.vk.loader import vk
from rgraph.vk.resources import HostBuffer
from rgraph.vk.scene_deform import DeformGPU, DeformPart

NORMAL_ATOL = 2e-6  # measured on lavapipe: <= 1.2e-7
TANGENT_ATOL = 5e-6  # measured: <= 2.2e-7


def hard_mesh() -> tuple[MeshData, np.ndarray]:
    """A sphere with hard cases appended; returns the rest mesh and its deformed positions."""
    base = make_shape("sphere", {"radius": 1.0, "segments": 12, "rings": 6})
    n = base.vertex_count
    pos = np.concatenate([base.positions, [[2.0, 0, 0], [2.0, 0, 0], [2.0, 0, 0], [5.0, 5.0, 5.0]]])
    nrm = np.concatenate([base.normals, np.tile([0.0, 0.0, 1.0], (4, 1))])
    extra = [[n, n + 1, n + 2],  # three coincident points
             [0, 0, 1],  # a repeated index
             [14, 15, 14]]  # another one on a vertex with real faces
    idx = np.concatenate([base.indices, np.array(extra, dtype=np.uint32)])
    rest = MeshData(pos, nrm, idx)
    moved = pos.copy()
    moved[20:24] = moved[20]  # collapsed vertices: their shared faces have zero area
    a, b = moved[30], moved[31]
    moved[32] = a + 0.5 * (b - a)  # vertex 32 between 30 and 31: one of its faces nearly a sliver
    return rest, moved


def scaled_sphere(scale: float) -> tuple[MeshData, np.ndarray]:
    s = make_shape("sphere", {"radius": 1.0, "segments": 10, "rings": 5})
    rest = MeshData(s.positions * scale + scale * np.array([3.0, -1.0, 2.0]), s.normals, s.indices)
    wobble = 1.0 + 0.1 * np.sin(7.0 * s.positions[:, 0])[:, None]
    return rest, (s.positions * wobble + np.array([3.0, -1.0, 2.0])) * scale


def parts_and_states() -> tuple[list[DeformPart], np.ndarray, np.ndarray]:
    neck = make_shape("neck", {"segments": 24, "stacks": 8})
    neck_pos = Deformer(neck).positions(0.85)
    meshes = [(neck, neck_pos), hard_mesh(), scaled_sphere(1e30), scaled_sphere(1e-30)]
    parts, cur, base = [], [], 0
    for data, moved in meshes:
        top = build_topology(data.vertex_count, data.indices, data.smooth_group, data.positions)
        parts.append(DeformPart(data, top, base))
        cur.append(moved)
        base += data.vertex_count
    cur_arr = np.concatenate(cur).astype(np.float32)
    prev_arr = np.concatenate([m[0].positions for m in meshes]).astype(np.float32)
    return parts, prev_arr, cur_arr


@pytest.fixture(scope="module")
def gpu_runs():
    """[(alpha, vertices (n, 6), tangents (n, 4))] for alpha 1, 1 again and 0.25; the messages."""
    parts, prev, cur = parts_and_states()
    v = vk()
    runs = []
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        local = DeviceLocal(gpu.device)
        hosts: list[HostBuffer] = []
        deform = None
        try:
            with one_time_submitter(gpu.device) as submit:
                def host(size: int, usage: int) -> HostBuffer:
                    hosts.append(HostBuffer.create(gpu.device, size, usage))
                    return hosts[-1]

                deform = DeformGPU(gpu.device, 1, parts, device_buffer=local.buffer, host_buffer=host,
                                   upload=lambda ups: local.upload(submit, ups))
                for alpha in (1.0, 1.0, 0.25):
                    deform.slots[2], deform.slots[5] = prev, cur  # any two ring slots
                    deform.set_header(0, alpha, 2, 5)
                    submit("graphics", lambda cb: deform.record(cb, 0))
                    src = (v.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, v.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT)
                    verts = np.frombuffer(local.read(submit, deform.vertex_buffers[0], *src), dtype=np.float32)
                    tans = np.frombuffer(local.read(submit, deform.tangent_buffers[0], *src), dtype=np.float32)
                    n = deform.total
                    runs.append((alpha, verts[:6 * n].reshape(n, 6), tans[:4 * n].reshape(n, 4)))
        finally:
            if deform is not None:
                deform.destroy()
            for h in hosts:
                h.destroy()
            local.destroy()
        messages = [str(m) for m in gpu.close()]
    return parts, prev, cur, runs, messages


def reference(parts, positions):
    out_n, out_t = [], []
    for part in parts:
        p = positions[part.base:part.base + part.data.vertex_count].astype(np.float64)
        n, t = normals_tangents(p, part.data.indices, part.topology, part.data.normals, part.data.uvs)
        out_n.append(n)
        out_t.append(t)
    return np.concatenate(out_n), np.concatenate(out_t)


def test_no_validation_messages_and_reproducible(gpu_runs):
    _parts, _prev, _cur, runs, messages = gpu_runs
    assert messages == []
    (_, v1, t1), (_, v2, t2), _ = runs
    assert v1.tobytes() == v2.tobytes() and t1.tobytes() == t2.tobytes()  # deterministic gather
    for _alpha, verts, tans in runs:
        assert np.isfinite(verts).all() and np.isfinite(tans).all()
        np.testing.assert_allclose(np.linalg.norm(verts[:, 3:], axis=1), 1.0, atol=1e-5)
        np.testing.assert_allclose(np.linalg.norm(tans[:, :3], axis=1), 1.0, atol=1e-5)
        assert set(np.unique(tans[:, 3])) <= {-1.0, 1.0}


@pytest.mark.parametrize("run", [0, 2])
def test_gpu_matches_the_float64_reference(gpu_runs, run):
    parts, prev, cur, runs, _messages = gpu_runs
    alpha, verts, tans = runs[run]
    mixed = prev.astype(np.float64) * (1.0 - alpha) + cur.astype(np.float64) * alpha
    scale = np.concatenate([np.full(p.data.vertex_count, 1.0 / p.topology.scale) for p in parts])[:, None]
    np.testing.assert_allclose(verts[:, :3] / scale, mixed / scale, rtol=0, atol=1e-6)
    if alpha == 1.0:
        assert np.array_equal(verts[:, :3], cur)  # alpha 1 is exactly the current state
    normals, tangents = reference(parts, verts[:, :3])
    np.testing.assert_allclose(verts[:, 3:], normals, rtol=0, atol=NORMAL_ATOL)
    np.testing.assert_allclose(tans[:, :3], tangents[:, :3], rtol=0, atol=TANGENT_ATOL)
    neck = parts[0].data.vertex_count
    assert np.array_equal(tans[:neck, 3], tangents[:neck, 3])  # handedness where the UVs are well defined


def test_hard_cases_fall_back_and_seams_share_normals(gpu_runs):
    parts, _prev, cur, runs, _messages = gpu_runs
    _, verts, _tans = runs[0]
    neck, hard = parts[0], parts[1]
    # the split neck's GPU normals equal the welded neck's CPU normals (the seam is invisible)
    n_side = 24 * 9
    welded_pos = cur[:n_side].astype(np.float64)
    idx = neck.data.indices.astype(np.int64)
    seam = (idx >= n_side) & (idx < n_side + 9)  # the seam column (row i) -> column 0 of row i
    welded_idx = np.where(seam, (idx - n_side) * 24, idx)
    side_tris = (idx < n_side + 9).all(axis=1)  # not the caps
    welded = vertex_normals(welded_pos, welded_idx[side_tris])
    np.testing.assert_allclose(verts[:n_side, 3:], welded, atol=NORMAL_ATOL)
    np.testing.assert_array_equal(verts[n_side:n_side + 9, 3:], verts[0:n_side:24, 3:])  # seam copies: same bits
    # hard cases: the coincident triple and the isolated vertex take their rest normals exactly
    b = hard.base
    n = hard.data.vertex_count
    np.testing.assert_array_equal(verts[b + n - 4:b + n, 3:], hard.data.normals[-4:].astype(np.float32))
    # the collapsed vertices still have real faces: smooth normals, not the fallback
    assert (np.einsum("ij,ij->i", verts[b + 20:b + 24, 3:], hard.data.normals[20:24]) > 0.0).all()
