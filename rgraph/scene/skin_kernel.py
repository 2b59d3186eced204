"""One logic state of an :class:`~rgraph.scene.animation.Animator`, packed into preallocated
buffers: the fast float32 path of ``Animator.state``, bit-identical to the reference
``pack_bones(forward_kinematics(local_pose))`` (rgraph.scene.skinning).

The same float32 operations in the same order per element, reorganised so that nothing is
allocated or computed twice and the interpreter does little:

- every array is preallocated and the whole tick is a *tape* built once: a list of NumPy calls
  (ufuncs with ``out=``, ``np.take(out=...)``) on fixed views of those buffers, run in order;
  only the first (scene time) and the stores into the caller's output vary per tick;
- the skeleton's depth levels are cut into pieces of at most ``piece`` bones, so that a
  piece's working set stays in the core's cache; each piece is packed to half floats right
  after it is computed;
- the animation's structure is used where the result is provably the same: non-root bones have
  a local scale of exactly 1, so every bone's object-space scale is its root's (``ps * 1``);
  local translations are the rest offsets broadcast over characters; the rotation's doubled
  cross product ``2 (u x v)`` takes the pre-doubled offset (``u x 2v``: scaling by two is
  exact); ``0.5 (amp sin)`` is ``(0.5 amp) sin``;
- the half conversion is ``half_bits``'s (the float32 bits of ``x 2^-112``, + 0x1000, >> 13,
  | the sign) on the signed value (its shifted sign bit is masked off); two halves are paired
  into each uint32 word of the output, so a bone is four strided stores, the scale (every
  bone's is its root's) paired in from one row per character;
- the translation clamp to the half range is skipped when a bound computed once (the rest
  offsets' lengths summed, times the largest root scale) proves it a no-op.

A non-finite scene time is a ValueError (the rig's constants are checked once): with finite
inputs every output is finite, which ``pack_bones`` checks on the reference path.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from rgraph.scene.skinning import HALF_MAX

if TYPE_CHECKING:
    from rgraph.scene.animation import Animator

F32 = np.float32
REBIAS = np.float32(2.0 ** -112)  # float32 exponent bias 127 -> half bias 15
ROOT_SCALE_MAX = 1.01  # Animator: the root breathes 1 +- 1%
ROOT_BOB = 0.02  # and bobs up to 2 cm
PIECE = 16  # bones per piece of a depth level
# the rows of ``world`` (t.xyz, q.xyzw) in a piece's half-bits scratch: first the low half of
# each output word (t.x, t.z, q.x, q.z), then the high (t.y, q.y, q.w; s is t.z's high half)
PAIR_ORDER = (0, 2, 3, 5, 1, 4, 6)


def supported(animator: Animator) -> bool:
    """Whether the kernel applies: float32, every depth level one contiguous range of bones
    (depth-sorted skeletons, as ``build_rig`` makes), one root, a little-endian host (the
    halves are paired into words)."""
    levels = animator.rig.skeleton.levels
    return (sys.byteorder == "little" and np.dtype(animator.dtype) == np.float32 and len(levels) > 0 and levels[0][0] == slice(0, 1)
            and all(isinstance(b, slice) for b, _ in levels))


class StateKernel:
    """The packed states of ``animator``'s characters ``chars`` (a range of them): see the
    module docstring."""

    def __init__(self, animator: Animator, chars: slice = slice(None), piece: int = PIECE) -> None:
        if not supported(animator):
            raise ValueError("StateKernel needs a float32 animator with a depth-sorted, single-root skeleton")
        sk = animator.rig.skeleton
        self.phase, self.omega = animator.phase[chars], animator.omega[chars]
        b, c = sk.bones, len(self.phase)
        self.bones, self.characters = b, c
        amp = animator._amp.astype(F32)[:, None]
        self.amp_half = amp * F32(0.5)
        self.bone_phase = animator._bone_phase.astype(F32)[:, None]
        axes = animator._axes.astype(F32)
        offsets = animator._offsets
        self.off = offsets.T[:, :, None].astype(F32)  # (3, B, 1): the local rest translations
        self.off2 = self.off + self.off
        for name, arr in (("amplitudes", amp), ("phases", self.bone_phase), ("axes", axes),
                          ("offsets", self.off), ("character phases", self.phase), ("speeds", self.omega)):
            if not np.isfinite(arr).all():
                raise ValueError(f"animation {name} must be finite")
        reach = float(np.linalg.norm(offsets[0])) + ROOT_BOB + ROOT_SCALE_MAX * float(
            np.linalg.norm(offsets[1:], axis=1).sum())
        self.clip_t = not reach * 1.01 < HALF_MAX  # otherwise clamping the translations changes nothing
        pieces = []
        for bones, parents in sk.levels[1:]:
            parents = np.asarray(parents, dtype=np.intp)
            for lo in range(bones.start, bones.stop, piece):
                hi = min(lo + piece, bones.stop)
                p = parents[lo - bones.start:hi - bones.start]
                one_range = np.array_equal(p, np.arange(p[0], p[0] + len(p)))
                pieces.append((slice(lo, hi), slice(int(p[0]), int(p[0]) + len(p)) if one_range else p))
        self.pieces = [slice(0, 1)] + [bones for bones, _ in pieces]
        widest = max(bones.stop - bones.start for bones in self.pieces)
        # buffers
        self.cycle = np.empty(c)  # float64: w_c t + phase_c (mod 2 pi)
        self.tmp64 = np.empty(c)
        self.cycle32 = np.empty(c, F32)
        self.s_root = np.empty(c, F32)
        self.angle = np.empty((b, c), F32)  # the bone angles, then sin(half angle)
        self.half = np.empty((b, c), F32)
        self.local_q = np.empty((4, b, c), F32)
        self.world = np.empty((7, b, c), F32)  # rows t.xyz, q.xyzw (object space)
        # per-piece scratch, (rows, n, C) contiguous views of flat buffers (a strided out= would
        # make NumPy buffer or copy): a piece's parents when they are not one range, the cross
        # product, two temporaries, its half bits (the low 16 bits of uint32) and signs
        self._flat = {name: np.empty(rows * widest * c, dtype) for name, rows, dtype in (
            ("gathered", 7, F32), ("cross", 3, F32), ("tmp", 2, F32), ("bits", 7, np.uint32), ("signs", 7, np.uint32))}
        self.s_bits = np.empty(c, np.uint32)
        # the tape: segments of NumPy calls, each piece's ending with its pack (then stored)
        self.segments: list[tuple[list[tuple[Callable[..., Any], tuple[Any, ...]]], slice | None]] = []
        self._segment(slice(0, 1))
        self._emit_local_and_root(axes)
        self._emit_scale()
        self._emit_pack(slice(0, 1))
        for bones, parents in pieces:
            self._segment(bones)
            self._emit_level(bones, parents)
            self._emit_pack(bones)

    def _scratch(self, name: str, rows: int, n: int) -> np.ndarray:
        return self._flat[name][:rows * n * self.characters].reshape(rows, n, self.characters)

    # ----------------------------------------------------------------- per tick
    def state(self, seconds: float, out: np.ndarray | None = None) -> np.ndarray:
        """The packed state at ``seconds``: (B, C, 8) half bits as uint16, into ``out`` when
        given (a (B, C, 8) uint16 array or view whose last axis is contiguous, e.g. a shared
        buffer's characters)."""
        if not np.isfinite(seconds):
            raise ValueError(f"scene time must be finite, not {seconds}")
        if out is None:
            out = np.empty((self.bones, self.characters, 8), np.uint16)
        words = out.view(np.uint32)  # (B, C, 4): two halves per word, the low one first (little-endian)
        np.multiply(self.omega, seconds, self.cycle)
        for tape, bones in self.segments:
            for f, args in tape:
                f(*args)
            if bones is not None:  # the piece's words, interleaved: (t.x|t.y, t.z|s, q.x|q.y, q.z|q.w)
                dst = words[bones]
                w = self._scratch("bits", 7, bones.stop - bones.start)
                for j in range(4):
                    np.copyto(dst[:, :, j], w[j])
        return out

    # ----------------------------------------------------------------- the tape
    def _segment(self, stores: slice | None) -> None:
        """Start a segment of the tape: after its calls, the halves of the bones ``stores``
        (None: nothing) go to the output."""
        self.segments.append(([], stores))

    def _op(self, f: Callable[..., Any], *args: Any) -> None:
        self.segments[-1][0].append((f, args))

    def _emit_local_and_root(self, axes: np.ndarray) -> None:
        """Scene time -> cycle (float64, as Animator.local_pose), local rotations (angle
        ``amp sin(cycle + phase_b)`` about each bone's axis), the root's transform."""
        op, cyc, t64 = self._op, self.cycle, self.tmp64
        op(np.add, cyc, self.phase, cyc)
        op(np.remainder, cyc, 2.0 * np.pi, cyc)
        op(np.copyto, self.cycle32, cyc, "same_kind")
        a, h, lq = self.angle, self.half, self.local_q
        op(np.add, self.cycle32[None, :], self.bone_phase, a)
        op(np.sin, a, a)
        op(np.multiply, a, self.amp_half, h)
        op(np.sin, h, a)
        for k in range(3):
            op(np.multiply, axes[:, k:k + 1], a, lq[k])
        op(np.cos, h, lq[3])
        w, root = self.world, slice(0, 1)
        op(np.copyto, w[0:3, root], self.off[:, root])
        op(np.sin, cyc, t64)  # the bob: float64, added into float32 (as the reference)
        op(np.absolute, t64, t64)
        op(np.multiply, t64, ROOT_BOB, t64)
        op(np.add, w[1, 0], t64, w[1, 0])
        op(np.copyto, w[3:7, root], lq[:, root])
        op(np.multiply, cyc, 2.0, t64)  # the breathing scale: 1 + 0.01 sin(2 cycle)
        op(np.sin, t64, t64)
        op(np.multiply, t64, 0.01, t64)
        op(np.add, t64, 1.0, self.s_root)

    def _emit_level(self, bones: slice, parents: slice | np.ndarray) -> None:
        """One piece of a depth level: q = q_parent * q_local, t = t_parent + s rotate(q_parent,
        offset) (skinning.qmul, skinning.qrot, operation for operation)."""
        op = self._op
        n = bones.stop - bones.start
        w = self.world
        if isinstance(parents, slice):
            p = w[:, parents]
        else:
            p = self._scratch("gathered", 7, n)
            op(np.take, w, parents, 1, p, "clip")
        tmp, tmp2 = self._scratch("tmp", 2, n)
        ax, ay, az, aw = p[3], p[4], p[5], p[6]
        bx, by, bz, bw = self.local_q[:, bones]
        qx, qy, qz, qw = w[3:7, bones]
        for dst, first, rest in ((qx, (aw, bx), ((np.add, ax, bw), (np.add, ay, bz), (np.subtract, az, by))),
                                 (qy, (aw, by), ((np.subtract, ax, bz), (np.add, ay, bw), (np.add, az, bx))),
                                 (qz, (aw, bz), ((np.add, ax, by), (np.subtract, ay, bx), (np.add, az, bw))),
                                 (qw, (aw, bw), ((np.subtract, ax, bx), (np.subtract, ay, by), (np.subtract, az, bz)))):
            op(np.multiply, *first, dst)
            for combine, x, y in rest:
                op(np.multiply, x, y, tmp)
                op(combine, dst, tmp, dst)
        u = (ax, ay, az)
        v, v2 = self.off[:, bones], self.off2[:, bones]
        c = self._scratch("cross", 3, n)
        for k in range(3):  # c = 2 (u x v) = u x 2v
            i, j = (k + 1) % 3, (k + 2) % 3
            op(np.multiply, u[i], v2[j], c[k])
            op(np.multiply, u[j], v2[i], tmp)
            op(np.subtract, c[k], tmp, c[k])
        for k in range(3):  # t = ((v + w c) + u x c) s + t_parent
            i, j = (k + 1) % 3, (k + 2) % 3
            dst = w[k, bones]
            op(np.multiply, aw, c[k], dst)
            op(np.add, dst, v[k], dst)
            op(np.multiply, u[i], c[j], tmp)
            op(np.multiply, u[j], c[i], tmp2)
            op(np.subtract, tmp, tmp2, tmp)
            op(np.add, dst, tmp, dst)
            op(np.multiply, dst, self.s_root, dst)
            op(np.add, dst, p[k], dst)

    def _emit_pack(self, bones: slice) -> None:
        """The piece's rows of ``world`` as half bits (skinning.half_bits), paired into the
        output's uint32 words in ``bits``: rows 0-3 hold ``lo | hi << 16`` of (t.x, t.y),
        (t.z, s), (q.x, q.y), (q.z, q.w)."""
        op = self._op
        n = bones.stop - bones.start
        rows = self.world[:, bones]
        bits, signs = self._scratch("bits", 7, n), self._scratch("signs", 7, n)
        for slot, r in enumerate(PAIR_ORDER):
            f = bits[slot].view(F32)
            if self.clip_t and r < 3:
                op(np.clip, rows[r], -HALF_MAX, HALF_MAX, f)
                op(np.multiply, f, REBIAS, f)
            else:
                op(np.multiply, rows[r], REBIAS, f)  # signed: the sign (bit 31) lands on bit 18, cleared below
            op(np.right_shift, rows[r].view(np.uint32), 16, signs[slot])
        op(np.add, bits, 0x1000, bits)
        op(np.right_shift, bits, 13, bits)
        op(np.bitwise_and, signs, 0x8000, signs)
        op(np.bitwise_or, bits, signs, bits)
        op(np.bitwise_and, bits[0:4], 0xFFFF, bits[0:4])  # the low halves
        op(np.left_shift, bits[4:7], 16, bits[4:7])  # the high halves, in place
        op(np.bitwise_or, bits[0], bits[4], bits[0])
        op(np.bitwise_or, bits[1], self.s_bits, bits[1])  # every bone's scale is its root's
        op(np.bitwise_or, bits[2:4], bits[5:7], bits[2:4])

    def _emit_scale(self) -> None:
        """The roots' scale as a high half (``s_bits``): half_bits(clip(s, 0, HALF_MAX)) << 16."""
        op, s, b = self._op, self.s_root, self.s_bits
        f = b.view(F32)
        op(np.clip, s, 0.0, HALF_MAX, f)
        op(np.multiply, f, REBIAS, f)
        op(np.add, b, 0x1000, b)
        op(np.right_shift, b, 13, b)
        op(np.left_shift, b, 16, b)
