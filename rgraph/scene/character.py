"""The procedural skinned character: a humanoid skeleton of up to 256 bones and its mesh.

The bone template, in priority order (parents first; ``bones: N`` keeps the first N, then sorted by depth): pelvis
(the root), 4 spine bones, neck, head, legs (thigh, shin, foot, toe), arms (clavicle, upper
arm, forearm, hand), 5 three-bone fingers per hand (53 bones so far), then hair strands of 4
bones hanging from the head until N is reached. Metres, +Y up, facing +Z, 1.78 m tall, T-pose.
The deepest chain (root to a fingertip) is 12 bones, so forward kinematics takes 12 vectorised
steps whatever N is.

The mesh is one capsule per bone (head to tail); a capsule's vertices follow its bone and,
near the joint, blend 50/50 into the parent over the first quarter of the bone (two influences
per vertex, weights as 8-bit unorm summing to exactly 255). About 6,000 triangles at 256 bones.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rgraph.scene.shapes import MeshData, capsule, merge, sphere
from rgraph.scene.skinning import MAX_BONES, Skeleton

X, Y, Z = np.eye(3)


@dataclass(frozen=True)
class Bone:
    parent: int
    head: tuple[float, float, float]
    tail: tuple[float, float, float]
    radius: float
    axis: np.ndarray  # animation: local rotation axis
    amplitude: float  # radians at amplitude 1
    phase: float  # radians
    segments: int = 8


@dataclass(frozen=True)
class Rig:
    """A character: skeleton, template bones, rest mesh and per-vertex influences."""

    skeleton: Skeleton
    bones: list[Bone]
    mesh: MeshData
    joints: np.ndarray  # (V, 4) uint8
    weights: np.ndarray  # (V, 4) uint8 unorm, rows sum to 255

    @property
    def weights_f(self) -> np.ndarray:
        return self.weights.astype(np.float64) / 255.0


def template(count: int) -> list[Bone]:
    """The first ``count`` bones of the template (1 <= count <= 256)."""
    if not 1 <= count <= MAX_BONES:
        raise ValueError(f"bones must be 1..{MAX_BONES}, got {count}")
    b: list[Bone] = [Bone(-1, (0, 0.95, 0), (0, 1.05, 0), 0.14, Y, 0.15, 0.0, 10)]
    for k in range(4):
        b.append(Bone(len(b) - 1, (0, 1.05 + 0.1 * k, 0), (0, 1.15 + 0.1 * k, 0), 0.13, Y, 0.08, 0.3 * k, 10))
    b.append(Bone(4, (0, 1.45, 0), (0, 1.55, 0), 0.05, X, 0.1, 0.0))
    b.append(Bone(5, (0, 1.55, 0), (0, 1.78, 0), 0.1, Y, 0.25, 0.5, 10))
    legs: list[int] = []
    for side in (1, -1):  # thighs first, then shins, feet, toes (priority by size)
        legs.append(len(b))
        b.append(Bone(0, (0.1 * side, 0.95, 0), (0.1 * side, 0.52, 0), 0.07, X, 0.5, np.pi * (side < 0)))
    segs = [((0.52, 0.0), (0.1, 0.0), 0.055, 0.4, 0.6), ((0.1, 0.0), (0.05, 0.15), 0.04, 0.2, 1.0),
            ((0.05, 0.15), (0.05, 0.22), 0.03, 0.1, 1.2)]
    for (y0, z0), (y1, z1), r, amp, ph in segs:
        for k, side in enumerate((1, -1)):
            parent = legs[k]
            legs[k] = len(b)
            b.append(Bone(parent, (0.1 * side, y0, z0), (0.1 * side, y1, z1), r, X, amp, ph + np.pi * (side < 0)))
    arms = [4, 4]
    for x0, x1, r, axis, amp in ((0.03, 0.18, 0.04, Z, 0.05), (0.18, 0.46, 0.045, Y, 0.5),
                                 (0.46, 0.72, 0.04, Y, 0.3), (0.72, 0.8, 0.035, Z, 0.2)):
        for k, side in enumerate((1, -1)):
            parent = arms[k]
            arms[k] = len(b)
            b.append(Bone(parent, (x0 * side, 1.42, 0), (x1 * side, 1.42, 0), r, axis, amp, np.pi * (side > 0)))
    for f in range(5):
        for k, side in enumerate((1, -1)):
            parent, z = arms[k], -0.03 + 0.015 * f
            for j in range(3):
                x0 = 0.8 + 0.025 * j
                b.append(Bone(parent, (x0 * side, 1.42, z), ((x0 + 0.025) * side, 1.42, z), 0.01, Z * side, 0.15,
                              0.4 * j, 4))
                parent = len(b) - 1
    strand = 0
    while len(b) < count:
        a = 2.4 * strand  # golden-angle-ish spread over the skull
        ring = 0.06 + 0.03 * ((strand * 7) % 3)
        d = np.array([np.sin(a), 0.0, np.cos(a)])
        parent, p = 6, np.array([0.0, 1.7, 0.0]) + ring * d
        for j in range(4):
            if len(b) >= count:
                break
            q = p + 0.045 * d + np.array([0.0, -0.035, 0.0])
            b.append(Bone(parent, tuple(p), tuple(q), 0.012, np.cross(Y, d), 0.12, 0.5 * j + a, 3))
            parent, p = len(b) - 1, q
        strand += 1
    return b[:count]


def _bone_capsule(bone: Bone) -> tuple[MeshData, np.ndarray]:
    """The capsule around a bone (head to tail) and each vertex's parameter along it (0..1)."""
    head, tail = np.asarray(bone.head, dtype=np.float64), np.asarray(bone.tail, dtype=np.float64)
    axis = tail - head
    length = float(np.linalg.norm(axis))
    rings = 2 if bone.segments > 4 else 1
    body = length - 2 * bone.radius
    m = (capsule(radius=bone.radius, height=body, segments=bone.segments, rings=rings) if body > 0.2 * bone.radius
         else sphere(radius=bone.radius, segments=bone.segments, rings=2 * rings + 1))  # short, fat bones
    y = axis / length
    x = np.cross(y, Z if abs(y[2]) < 0.9 else X)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    rot = np.stack([x, y, z], axis=1)  # columns: the capsule's x, y, z in object space
    pos = m.positions @ rot.T + (head + tail) / 2
    u = np.clip(((pos - head) @ y) / length, 0.0, 1.0)
    return MeshData(pos, m.normals @ rot.T, m.indices), u


def _depth_sorted(bones: list[Bone]) -> list[Bone]:
    """The bones in order of depth (stable), parents renumbered: every level of the hierarchy is
    a contiguous range, which forward kinematics slices without copies."""
    depth: list[int] = []
    for b in bones:
        depth.append(0 if b.parent < 0 else depth[b.parent] + 1)
    order = sorted(range(len(bones)), key=lambda k: depth[k])
    new = {old: k for k, old in enumerate(order)}
    return [replace(bones[k], parent=new[bones[k].parent] if bones[k].parent >= 0 else -1) for k in order]


def build_rig(count: int) -> Rig:
    """The character with ``count`` bones (module docstring)."""
    bones = _depth_sorted(template(count))
    skeleton = Skeleton(np.array([b.parent for b in bones]), np.array([b.head for b in bones]))
    parts, joints, weights = [], [], []
    for k, bone in enumerate(bones):
        mesh, u = _bone_capsule(bone)
        parts.append(mesh)
        own = np.full(len(u), 255, dtype=np.int64)
        if bone.parent >= 0:  # 50/50 at the joint, all own from a quarter of the bone on
            own = np.rint(255 * (0.5 + 0.5 * np.clip(u / 0.25, 0.0, 1.0))).astype(np.int64)
        j = np.zeros((len(u), 4), dtype=np.uint8)
        w = np.zeros((len(u), 4), dtype=np.uint8)
        j[:, 0], j[:, 1] = k, max(bone.parent, 0)
        w[:, 0], w[:, 1] = own, 255 - own
        joints.append(j)
        weights.append(w)
    return Rig(skeleton, bones, merge(parts), np.concatenate(joints), np.concatenate(weights))


def character() -> MeshData:
    """The 256-bone character in its rest pose (``shape: character`` without ``skinned``)."""
    return build_rig(MAX_BONES).mesh
