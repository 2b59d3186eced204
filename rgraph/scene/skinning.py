"""Skeletal skinning in NumPy: forward kinematics, skinning transforms, half-float bone packing,
interpolation between two logic states and linear-blend skinning (the reference of the GPU path).

A bone transform is a similarity: rotation quaternion ``q`` (x, y, z, w), translation ``t`` and
uniform scale ``s``: ``x -> t + s * rotate(q, x)``. Batched over B bones of C characters,
component-major (``q`` is (4, B, C)) so that every operation is a few whole-array ops. The rest pose has identity rotations and unit scales; bone ``b``'s rest joint
(its head) is ``Skeleton.heads[b]`` in object space, so its inverse bind is a translation.

Packed bones (``shaders/scene/skinning.glsl``): 8 half floats = 16 bytes = one ``uvec4`` per
bone: ``(t.x, t.y, t.z, s, q.x, q.y, q.z, q.w)``, bone-major (entry ``b * C + c``). Logic states
hold the joint transforms (forward kinematics' output); the vertex shader applies the inverse
bind (``p - head``) after interpolating, so joints move along straight lines between states. Values are clamped to the half range
(``HALF_MAX``), the scale to ``[0, HALF_MAX]``; a non-finite input is a ValueError (never a NaN
on the GPU). Interpolation (:func:`interpolate`, identical on the GPU): lerp of ``t`` and ``s``,
normalised lerp of ``q`` along the shortest arc (``q1`` negated when ``dot(q0, q1) < 0``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

HALF_MAX = 65504.0
BONE_BYTES = 16
MAX_BONES = 256  # joint indices are 8-bit


@dataclass(frozen=True)
class Skeleton:
    """``parents[b]`` (< b, -1 for a root) and rest joint positions ``heads`` (B, 3)."""

    parents: np.ndarray
    heads: np.ndarray
    levels: list[tuple[slice | np.ndarray, np.ndarray]] = field(init=False, repr=False, compare=False)
    depths: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        parents = np.asarray(self.parents, dtype=np.int64)
        if np.any(parents >= np.arange(len(parents))):
            raise ValueError("every bone's parent must come before it (parents[b] < b)")
        depth = np.zeros(len(parents), dtype=np.int64)
        for b, p in enumerate(parents):
            depth[b] = 0 if p < 0 else depth[p] + 1
        levels = []
        for d in range(int(depth.max(initial=-1)) + 1):
            bones = np.nonzero(depth == d)[0]
            contiguous = bones[-1] - bones[0] + 1 == len(bones)  # depth-sorted skeletons: a view, no copy
            levels.append((slice(int(bones[0]), int(bones[-1]) + 1) if contiguous else bones, parents[depth == d]))
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "heads", np.asarray(self.heads, dtype=np.float64).reshape(-1, 3))
        object.__setattr__(self, "levels", levels)
        object.__setattr__(self, "depths", depth)

    @property
    def bones(self) -> int:
        return len(self.parents)

    @property
    def depth(self) -> int:
        return len(self.levels)

    def rest_offsets(self) -> np.ndarray:
        """Local rest translations: head minus the parent's head (the head itself for roots)."""
        par = np.where(self.parents < 0, 0, self.parents)
        return self.heads - np.where(self.parents[:, None] < 0, 0.0, self.heads[par])


@dataclass
class Pose:
    """Batched bone transforms, component-major for vectorised speed: ``q`` (4, B, C) xyzw,
    ``t`` (3, B, C), ``s`` (B, C) for B bones of C characters (float32 or float64)."""

    q: np.ndarray
    t: np.ndarray
    s: np.ndarray


def qmul(a, b) -> np.ndarray:
    """Hamilton product of component-major xyzw quaternions (``a[0]`` is x)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])


def _cross(a, b) -> np.ndarray:
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def qrot(q, v) -> np.ndarray:
    """Component-major ``v`` (3, ...) rotated by unit ``q`` (4, ...): v + 2w (u x v) + 2 u x (u x v)."""
    u, w = q[:3], q[3]
    c = _cross(u, v)
    c += c
    return v + w * c + _cross(u, c)


def axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Component-major quaternions (4, B, C) for unit ``axis`` (B, 3) and ``angle`` (B, C) radians."""
    half = 0.5 * angle
    sin = np.sin(half)
    return np.stack([axis[:, 0:1] * sin, axis[:, 1:2] * sin, axis[:, 2:3] * sin, np.cos(half)])


def forward_kinematics(skeleton: Skeleton, local: Pose) -> Pose:
    """Object-space bone transforms from local ones (child = parent o local), one depth level
    of the hierarchy at a time, vectorised over characters and the level's bones."""
    q, t, s = np.empty_like(local.q), np.empty_like(local.t), np.empty_like(local.s)
    for depth, (bones, parents) in enumerate(skeleton.levels):
        lq, lt, ls = local.q[:, bones], local.t[:, bones], local.s[bones]
        if depth == 0:  # the roots
            q[:, bones], t[:, bones], s[bones] = lq, lt, ls
            continue
        pq, ps = q[:, parents], s[parents]
        q[:, bones] = qmul(pq, lq)
        rotated = qrot(pq, lt)
        rotated *= ps
        rotated += t[:, parents]
        t[:, bones] = rotated
        s[bones] = ps * ls
    return Pose(q, t, s)


def skin_transforms(skeleton: Skeleton, world: Pose) -> Pose:
    """Skinning transforms (rest object space -> posed): the bone's transform after its
    inverse bind, ``T(-head)``: same q and s, t - s * rotate(q, head)."""
    heads = skeleton.heads.T[:, :, None].astype(world.t.dtype)
    return Pose(world.q, world.t - world.s * qrot(world.q, np.broadcast_to(heads, world.t.shape)), world.s)


def half_bits(x: np.ndarray) -> np.ndarray:
    """float32 -> IEEE half bits (uint16) for finite ``|x| <= HALF_MAX``, rounding half away
    from zero (subnormals included): rebias the exponent by a multiply, round, shift."""
    x = np.asarray(x, dtype=np.float32)
    bits = (np.abs(x) * np.float32(2.0 ** -112)).view(np.uint32)
    bits += 0x1000
    bits >>= 13
    bits |= (x.view(np.uint32) >> 16) & 0x8000
    return bits.astype(np.uint16)


def _finite(*arrays: np.ndarray) -> bool:
    # one reduction each; only a non-finite sum (NaN, infinity or an overflowing total) looks closer
    return all(np.isfinite(a.sum()) or np.isfinite(a).all() for a in arrays)


def pack_bones(pose: Pose) -> np.ndarray:
    """(B, C, 8) float16 ``(t, s, q)`` (bone-major: entry ``b * C + c``); clamped to the half
    range, the scale to [0, HALF_MAX]. A non-finite value is a ValueError."""
    if not _finite(pose.t, pose.s, pose.q):
        raise ValueError("bone transforms must be finite (a NaN or infinity reached the bone packing)")
    planes = [half_bits(np.clip(pose.t, -HALF_MAX, HALF_MAX)), half_bits(np.clip(pose.s, 0.0, HALF_MAX))[None],
              half_bits(pose.q)]
    return np.stack([p for group in planes for p in group], axis=-1).view(np.float16)


def unpack_bones(packed: np.ndarray) -> Pose:
    """float64 :class:`Pose` of packed (B, C, 8) bones (what the GPU reads)."""
    p = np.moveaxis(np.asarray(packed).view(np.float16).astype(np.float64), -1, 0)
    return Pose(p[4:8], p[0:3], p[3])


def interpolate(a: Pose, b: Pose, alpha: float) -> Pose:
    """Between logic states ``a`` (alpha 0) and ``b`` (alpha 1): lerp t and s, shortest-arc
    normalised lerp of q (never NaN: after the sign flip |q0 + q1| >= sqrt(2) for unit inputs)."""
    flip = np.where(np.sum(a.q * b.q, axis=0) < 0.0, -1.0, 1.0)
    q = a.q + alpha * (b.q * flip - a.q)
    n = np.sqrt(np.sum(q * q, axis=0))
    ok = n > 1e-30
    q = np.where(ok, q / np.where(ok, n, 1.0), np.array([0.0, 0.0, 0.0, 1.0]).reshape(4, *([1] * n.ndim)))
    return Pose(q, a.t + alpha * (b.t - a.t), a.s + alpha * (b.s - a.s))


def skin(positions: np.ndarray, normals: np.ndarray, joints: np.ndarray, weights: np.ndarray,
         pose: Pose, character: int) -> tuple[np.ndarray, np.ndarray]:
    """Linear-blend skinning of one character (float64): each influence's transform applied,
    blended by weight; normals rotated and renormalised. ``pose`` holds skinning transforms."""
    j = np.asarray(joints, dtype=np.int64)
    q = pose.q[:, j, character].astype(np.float64)  # (4, V, 4 influences)
    n = np.sqrt(np.sum(q * q, axis=0))
    q = q / np.where(n > 1e-30, n, 1.0)
    t, s = pose.t[:, j, character].astype(np.float64), pose.s[j, character].astype(np.float64)
    w = np.asarray(weights, dtype=np.float64)
    p = (w * (t + s * qrot(q, np.broadcast_to(positions.T[:, :, None], t.shape)))).sum(axis=-1).T
    nn = (w * qrot(q, np.broadcast_to(normals.T[:, :, None], t.shape))).sum(axis=-1).T
    length = np.linalg.norm(nn, axis=-1, keepdims=True)
    nn = np.where(length > 1e-30, nn / np.where(length > 1e-30, length, 1.0), normals)
    return p, nn
