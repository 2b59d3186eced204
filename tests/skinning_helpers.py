"""Shared by the skinning tests: a two-character scene written on the fly, graphs/clustered.yaml
with the ``skin_readback`` pass or chosen intermediates as outputs, one validated run of it
(zero messages asserted) and the float64 reference pose (passes/skinning_ref.py) of the same
half-float logic states."""

from __future__ import annotations

import numpy as np
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


def skin_graph(tmp_path, readback_bytes: int | None, outputs=()):
    """graphs/clustered.yaml (its draw.mode default) with ``outputs`` made outputs and, with
    ``readback_bytes``, the ``skin_readback`` pass writing the output buffer ``skinned``."""
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


def run_skinned(tmp_path, *, bones=256, frames=1, params=None, readback=True, outputs=(), floor=True, size=SIZE):
    """(scene data, the skinned mesh, outputs) of one validated run of the two-character scene."""
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.executor import execute_plan

    scene = tmp_path / "skin_case.yaml"
    text = SCENE.replace("BONES", str(bones))
    scene.write_text(text if floor else "\n".join(ln for ln in text.splitlines() if "shape: plane" not in ln))
    data = load_scene_data(scene, size)
    mesh = data.skinned[0]
    readback_bytes = 2 * mesh.instances * mesh.data.vertex_count * 16
    plan = compile_graph(skin_graph(tmp_path, readback_bytes if readback else None, outputs), scene_path=scene, size=size,
                         params={"clusters.tile": "16", "clusters.slices": "4", **(params or {})})
    plan["logic_hz"] = LOGIC_HZ
    result = execute_plan(plan, validate=True, frames=frames, read_outputs=True)
    assert [m.text for m in result.messages] == []
    return data, mesh, result.outputs


def reference_pose(mesh, frame: int, alpha: float | None) -> tuple[np.ndarray, np.ndarray]:
    """(instances, V, 3) posed object-space positions and unit normals of frame ``frame`` from
    the half-float states, float64 (``alpha``: override the frame's interpolation factor)."""
    tick, frame_alpha = logic_tick(frame / 60.0, LOGIC_HZ)
    return reference_pose_of_ticks(mesh, tick - 1, tick, frame_alpha if alpha is None else alpha, LOGIC_HZ)


def reference_pose_of_ticks(mesh, previous: int, current: int, alpha: float, hz: float) -> tuple[np.ndarray, np.ndarray]:
    """``reference_pose`` between logic states ``previous`` and ``current`` (at ``hz``) at ``alpha``."""
    a, b = (unpack_bones(mesh.animator.state(k, hz)) for k in (previous, current))
    pose = interpolate(a, b, alpha)  # joint transforms
    rig, out_p, out_n = mesh.animator.rig, [], []
    for c in range(mesh.instances):
        joints = [ref.similarity(pose.q[:, j, c], pose.t[:, j, c], pose.s[j, c]) for j in range(rig.skeleton.bones)]
        skins = ref.skin_matrices(rig.skeleton.heads, joints)
        out_p.append(ref.skin_vertices(rig.mesh.positions, rig.joints, rig.weights_f, skins))
        n = np.stack([sum(w * skins[j][:3, :3] / pose.s[j, c] for j, w in zip(js, ws, strict=True) if w)
                      @ nv for js, ws, nv in zip(rig.joints, rig.weights_f, rig.mesh.normals, strict=True)])
        out_n.append(n / np.linalg.norm(n, axis=1, keepdims=True))
    return np.stack(out_p), np.stack(out_n)


def readback_pose(mesh, outputs) -> tuple[np.ndarray, np.ndarray]:
    """The ``skinned`` buffer of ``skin_readback``: (instances, V, 3) positions and unit normals."""
    v = np.frombuffer(outputs["skinned"].tobytes(), dtype=np.float32).reshape(2, mesh.instances, -1, 4)
    n = v[1, ..., :3].astype(np.float64)
    return v[0, ..., :3].astype(np.float64), n / np.linalg.norm(n, axis=-1, keepdims=True)


def clip_of(world: np.ndarray, view_proj) -> np.ndarray:
    """(..., 4) clip coordinates of camera-relative world points."""
    homo = np.concatenate([world, np.ones(world.shape[:-1] + (1,))], axis=-1)
    return homo @ np.asarray(view_proj, dtype=np.float64).T
