"""Skinning on lavapipe under validation + synchronization validation (zero messages):

- the GPU's posed vertices (``skin_readback``: shaders/scene/skinning.glsl, the vertex shaders'
  code) against the float64 matrix reference (passes/skinning_ref.py) of the same half-float
  logic states, at alpha 0, 0.5 and 1, for two characters with their own skeletons;
- the animation advances from one logic state to the next (frames at a 30 Hz logic rate);
- graphs/clustered.yaml draws the characters: the forward pass's depth_read test passes on every
  pixel the (skinned) depth prepass covered - the two vertex shaders pose identically - and the
  nearest depth is the nearest posed vertex's.
"""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT
from ruamel.yaml import YAML

from rgraph.resources import builtin_passes

builtin_passes()
from rgraph.passes import skinning_ref as ref  # noqa: E402

from rgraph.scene.animation import logic_tick  # noqa: E402
from rgraph.scene.build import load_scene_data  # noqa: E402
from rgraph.scene.skinning import interpolate, unpack_bones  # noqa: E402

SCENE = """scene: 1
name: skin_case
camera: {position: [0.0, 1.2, 4.0], look_at: [0.0, 1.0, 0.0], fov_y: 50, near: 0.1}
lights:
  - {type: directional, direction: [-0.4, -1.0, -0.6], intensity: 3.0}
materials:
  body:  {base_color: [0.72, 0.55, 0.45], roughness: 0.6, metallic: 0}
  floor: {base_color: [0.35, 0.35, 0.38], roughness: 0.8, metallic: 0}
meshes:
  - {shape: plane, params: {size: [20, 20], subdivisions: 1}, material: floor}
  - {shape: character, material: body, skinned: {bones: BONES, speed: 1.0, seed: 3, amplitude: 2.0},
     instances: {grid: [2, 1, 1], spacing: 1.8}}
"""
SIZE = (64, 48)
LOGIC_HZ = 30.0


def _graph(tmp_path, readback_bytes: int | None, outputs=()):
    y = YAML()
    doc = y.load((ROOT / "graphs" / "clustered.yaml").read_text())
    doc.pop("scene", None)
    for n in outputs:
        doc["resources"][n]["lifetime"] = "output"
    doc["outputs"] = list(doc["outputs"]) + list(outputs)
    if readback_bytes:
        doc["resources"]["skinned"] = {"kind": "buffer", "bytes": readback_bytes, "lifetime": "output"}
        doc["passes"]["skin_readback"] = {"kind": "compute", "impl": "skin_readback",
                                          "writes": {"skinned": "storage_write"}}
        doc["outputs"].append("skinned")
        doc["params"]["skin_readback.alpha"] = -1.0
    p = tmp_path / "skin_graph.yaml"
    with p.open("w") as f:
        y.dump(doc, f)
    return p


def _run(tmp_path, *, bones=256, frames=1, params=None, readback=True, outputs=(), floor=True):
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.executor import execute_plan

    scene = tmp_path / "skin_case.yaml"
    text = SCENE.replace("BONES", str(bones))
    scene.write_text(text if floor else "\n".join(ln for ln in text.splitlines() if "shape: plane" not in ln))
    data = load_scene_data(scene, SIZE)
    mesh = data.skinned[0]
    size = 2 * mesh.instances * mesh.data.vertex_count * 16
    plan = compile_graph(_graph(tmp_path, size if readback else None, outputs), scene_path=scene, size=SIZE,
                         params={"clusters.tile": "16", "clusters.slices": "4", **(params or {})})
    plan["logic_hz"] = LOGIC_HZ
    result = execute_plan(plan, validate=True, frames=frames, read_outputs=True)
    assert [m.text for m in result.messages] == []
    return data, mesh, result.outputs


def _reference(mesh, frame: int, alpha: float | None) -> tuple[np.ndarray, np.ndarray]:
    """(instances, V, 3) posed positions and unit normals from the half-float states, float64."""
    tick, frame_alpha = logic_tick(frame / 60.0, LOGIC_HZ)
    a, b = (unpack_bones(mesh.animator.state(k, LOGIC_HZ)) for k in (tick - 1, tick))
    pose = interpolate(a, b, frame_alpha if alpha is None else alpha)  # joint transforms
    rig, out_p, out_n = mesh.animator.rig, [], []
    for c in range(mesh.instances):
        joints = [ref.similarity(pose.q[:, j, c], pose.t[:, j, c], pose.s[j, c]) for j in range(rig.skeleton.bones)]
        skins = ref.skin_matrices(rig.skeleton.heads, joints)
        out_p.append(ref.skin_vertices(rig.mesh.positions, rig.joints, rig.weights_f, skins))
        n = np.stack([sum(w * skins[j][:3, :3] / pose.s[j, c] for j, w in zip(js, ws, strict=True) if w)
                      @ nv for js, ws, nv in zip(rig.joints, rig.weights_f, rig.mesh.normals, strict=True)])
        out_n.append(n / np.linalg.norm(n, axis=1, keepdims=True))
    return np.stack(out_p), np.stack(out_n)


def _gpu(mesh, outputs) -> tuple[np.ndarray, np.ndarray]:
    v = np.frombuffer(outputs["skinned"].tobytes(), dtype=np.float32).reshape(2, mesh.instances, -1, 4)
    n = v[1, ..., :3].astype(np.float64)
    return v[0, ..., :3].astype(np.float64), n / np.linalg.norm(n, axis=-1, keepdims=True)


@pytest.mark.vulkan
@pytest.mark.parametrize("alpha", [0.0, 0.5, 1.0])
def test_gpu_skinning_matches_the_reference(tmp_path, alpha):
    _data, mesh, out = _run(tmp_path, frames=2, params={"skin_readback.alpha": str(alpha)})
    got_p, got_n = _gpu(mesh, out)
    want_p, want_n = _reference(mesh, 1, alpha)
    assert np.abs(got_p - want_p).max() < 2e-5  # float32 of the same half inputs, ~2 m coordinates
    assert np.abs(got_n - want_n).max() < 1e-4
    rest = mesh.data.positions
    assert np.abs(got_p[0] - rest).max() > 0.05 and np.abs(got_p[0] - got_p[1]).max() > 0.05  # posed, each its own


@pytest.mark.vulkan
def test_gpu_interpolates_along_the_shortest_arc(tmp_path, monkeypatch):
    """Odd logic states store every quaternion negated (the same rotations): interpolating
    without the sign flip would swing the long way round."""
    from rgraph.scene.animation import Animator

    plain = Animator.state

    def flipped(self, tick, hz=60.0):
        packed = plain(self, tick, hz)
        if tick % 2:
            packed = packed.copy()
            packed[..., 4:8] = -packed[..., 4:8]
        return packed

    monkeypatch.setattr(Animator, "state", flipped)
    _data, mesh, out = _run(tmp_path, bones=64, frames=2)  # frame 1: states -1 (flipped) -> 0 at 0.5
    want = _reference(mesh, 1, None)[0]
    assert np.abs(_gpu(mesh, out)[0] - want).max() < 2e-5
    monkeypatch.setattr(Animator, "state", plain)
    assert np.abs(_reference(mesh, 1, None)[0] - want).max() < 1e-9  # the same poses either way


@pytest.mark.vulkan
def test_animation_advances_between_logic_states(tmp_path):
    # 30 Hz logic, 60 Hz frames: frame 1 is halfway from state -1 to 0, frame 2 is state 0 -> 1 at 0
    got = {}
    for frames in (1, 2, 3):
        _data, mesh, out = _run(tmp_path, bones=64, frames=frames)
        got[frames - 1] = _gpu(mesh, out)[0]
        want = _reference(mesh, frames - 1, None)[0]
        assert np.abs(got[frames - 1] - want).max() < 2e-5, frames
    assert logic_tick(1 / 60.0, LOGIC_HZ) == (0, pytest.approx(0.5))
    start = _reference(mesh, 0, 0.0)[0]  # state -1
    end = _reference(mesh, 0, 1.0)[0]  # state 0
    assert np.abs(end - start).max() > 1e-3  # the states differ
    # alpha 0.5 of the interpolation lies between them, not at either end
    assert np.abs(got[1] - start).max() > 1e-4 and np.abs(got[1] - end).max() > 1e-4
    assert np.allclose(got[2], end, atol=2e-5)  # frame 2 shows state 0 at alpha 0


@pytest.mark.vulkan
def test_clustered_draws_skinned_characters_without_depth_holes(tmp_path):
    _data, mesh, out = _run(tmp_path, readback=False, outputs=("depth", "hdr"), floor=False)
    depth = out["depth"].reshape(SIZE[1], SIZE[0])
    hdr = out["hdr"].reshape(SIZE[1], SIZE[0], -1)[..., :3].astype(np.float64)
    covered = depth > 0
    lit = hdr.sum(axis=-1) > 0
    assert covered.sum() > 0.03 * covered.size
    assert np.array_equal(lit, covered)  # forward's depth_read test passed on every prepass pixel
    # the nearest pixel is the nearest posed vertex (depth is affine over a screen triangle, so no
    # pixel is nearer than the nearest vertex, and a vertex facing the camera is covered)
    cam = _data.camera(0)
    world = _reference(mesh, 0, None)[0] + mesh.positions[:, None, :] - cam.position
    clip = np.concatenate([world, np.ones(world.shape[:-1] + (1,))], axis=-1) @ np.asarray(cam.view_proj).T
    nearest = (clip[..., 2] / clip[..., 3]).max()
    assert nearest * 0.97 < depth.max() <= nearest * 1.0001
