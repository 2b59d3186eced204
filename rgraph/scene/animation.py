"""Procedural animation of skinned characters at the logic rate, vectorised over characters.

Every character (instance) of a skinned mesh has its own skeleton state: a phase and a speed
drawn from ``numpy.random.default_rng(seed)`` (phase in [0, 2 pi), speed x [0.8, 1.2]). Bone
``b`` of character ``c`` at time ``t`` turns about its template axis by
``amplitude * a_b * sin(w_c t + phase_c + phase_b)`` (``w_c = 2 pi speed speed_c``); the root
also bobs (2 cm) and breathes (scale 1 +- 1%). Logic state ``k`` is the pose at ``t = k / hz``;
the renderer shows ``interpolate(state k - 1, state k, alpha)`` (rgraph.scene.skinning), the
study's two bone textures.

``Animator.state`` evaluates a state with ``rgraph.scene.skin_kernel`` (preallocated buffers, a
tape of NumPy calls), bit-identical to ``reference_state`` (``pack_bones`` of ``pose``: the
readable path, also the float64 one).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from rgraph.scene.character import Rig
from rgraph.scene.skin_kernel import StateKernel, supported
from rgraph.scene.skinning import Pose, axis_angle, forward_kinematics, pack_bones

LOGIC_HZ = 60.0


@dataclass
class Animator:
    """The characters of one skinned mesh: ``characters`` instances of ``rig``."""

    rig: Rig
    characters: int
    speed: float = 1.0  # cycles per second
    amplitude: float = 1.0  # multiplies every bone's template amplitude
    seed: int = 0
    dtype: type = np.float32  # the logic path; tests run float64 too
    _axes: np.ndarray = field(init=False, repr=False)
    _amp: np.ndarray = field(init=False, repr=False)
    _bone_phase: np.ndarray = field(init=False, repr=False)
    _offsets: np.ndarray = field(init=False, repr=False)
    _kernels: dict[int, list[tuple[StateKernel, slice]]] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        rng = np.random.default_rng(self.seed)
        self.phase = rng.uniform(0.0, 2.0 * np.pi, self.characters)
        self.omega = 2.0 * np.pi * self.speed * rng.uniform(0.8, 1.2, self.characters)
        bones = self.rig.bones
        self._axes = np.array([b.axis for b in bones], dtype=np.float64)
        self._amp = self.amplitude * np.array([b.amplitude for b in bones])
        self._bone_phase = np.array([b.phase for b in bones])
        self._offsets = self.rig.skeleton.rest_offsets()
        self._kernels = {}

    def __getstate__(self) -> dict:
        """Pickled without the kernels' buffers (a worker process builds its own)."""
        return {**self.__dict__, "_kernels": {}}

    @property
    def bones(self) -> int:
        return self.rig.skeleton.bones

    def local_pose(self, seconds: float, chars: slice = slice(None)) -> Pose:
        """Local transforms (component-major, B bones x C characters) at ``seconds``, of the
        characters ``chars`` (all by default)."""
        b, f = self.bones, self.dtype
        cycle = (self.omega[chars] * seconds + self.phase[chars]) % (2.0 * np.pi)  # (C,) float64, then float32
        c = len(cycle)
        angle = self._amp.astype(f)[:, None] * np.sin(cycle.astype(f)[None, :] + self._bone_phase.astype(f)[:, None])
        q = axis_angle(self._axes.astype(f), angle)
        t = np.empty((3, b, c), dtype=f)
        t[...] = self._offsets.T[:, :, None]
        t[1, 0] += 0.02 * np.abs(np.sin(cycle))
        s = np.ones((b, c), dtype=f)
        s[0] = 1.0 + 0.01 * np.sin(2.0 * cycle)
        return Pose(q, t, s)

    def pose(self, seconds: float, chars: slice = slice(None)) -> Pose:
        """Object-space joint transforms (rest joint frame -> posed) at ``seconds``: what a logic
        state holds; ``skin_transforms`` of it maps rest vertices (the GPU does that per vertex)."""
        return forward_kinematics(self.rig.skeleton, self.local_pose(seconds, chars))

    def state(self, tick: int, hz: float = LOGIC_HZ, threads: int = 1, out: np.ndarray | None = None) -> np.ndarray:
        """Logic state ``tick``: packed joint transforms (B, C, 8) float16 at ``t = tick / hz``,
        into ``out`` when given (any (B, C, 8) 16-bit array or view); with ``threads`` > 1 the
        characters are split into that many chunks evaluated on a thread pool (NumPy releases
        the GIL inside its array loops). Bit-identical to :meth:`reference_state`."""
        if not supported(self):
            state = self.reference_state(tick, hz)
            if out is not None:
                out.view(np.uint16)[...] = state.view(np.uint16)
                return out
            return state
        n = max(1, min(int(threads), self.characters // 64 or 1))
        if n not in self._kernels:
            edges = np.linspace(0, self.characters, n + 1).astype(int)
            chunks = [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]
            self._kernels[n] = [(StateKernel(self, chars), chars) for chars in chunks]
        if out is None:
            out = np.empty((self.bones, self.characters, 8), dtype=np.float16)
        bits = out.view(np.uint16)
        seconds = tick / hz
        kernels = self._kernels[n]
        if n == 1:
            kernels[0][0].state(seconds, bits)
        else:
            list(_pool(n).map(lambda kc: kc[0].state(seconds, bits[:, kc[1]]), kernels))
        return out

    def reference_state(self, tick: int, hz: float = LOGIC_HZ) -> np.ndarray:
        """Logic state ``tick`` the readable way: ``pack_bones(pose(tick / hz))`` (any dtype)."""
        return pack_bones(self.pose(tick / hz))


_POOLS: dict[int, ThreadPoolExecutor] = {}


def _pool(n: int) -> ThreadPoolExecutor:
    if n not in _POOLS:
        _POOLS[n] = ThreadPoolExecutor(n, thread_name_prefix="rgraph-skin")
    return _POOLS[n]


def logic_tick(seconds: float, hz: float = LOGIC_HZ) -> tuple[int, float]:
    """(tick k, alpha) of render time ``seconds``: show state k - 1 -> k at alpha in [0, 1)."""
    x = seconds * hz
    k = int(np.floor(x + 1e-9))
    return k, min(max(x - k, 0.0), 1.0)
