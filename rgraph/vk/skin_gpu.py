"""Skinning data on the GPU: set 0 bindings 7-9 of ``shaders/scene/skinning.glsl`` (owned by SceneGPU).

- binding 7 ``SkinVertices``: per vertex of the rigid vertex buffer (indexed by
  ``gl_VertexIndex``: the TLSF-placed base of the mesh plus the index, in every draw mode), 4 joint indices (uint8) and 4 weights (unorm8) as a ``uvec2``; written
  once (zeros outside skinned meshes). A 16-byte placeholder when the scene has no skinning.
- binding 8 ``Bones``: a header, then a ring of logic-state slots. Header: per scene mesh
  (``Draw.info.y``) a ``uvec4`` whose x is the first entry of that mesh's rest joint positions
  (``head``, float32 bits in xyz), then those heads. A slot: the packed joint transforms of
  every skinned instance (rgraph.scene.skinning: 16 bytes per bone, bone-major per mesh). Each
  logic state is packed and written once, into a slot no frame in flight reads (``SLOTS``:
  two per frame set, the logic's published pair and the one being written); the study's
  "two bone textures" are the two slots a frame set names. With a logic thread the thread
  writes its states there itself (``write_slot``); the render thread only names the slots.
  Graph param ``skin.worker``: ``process`` (default) evaluates the states in a worker process
  (rgraph.scene.skin_worker: the logic thread only waits for it and copies each state into
  its slot, holding the GIL for microseconds per tick); ``thread`` on the logic thread itself.
- binding 9 ``SkinFrame`` (per frame set, std140): ``(alpha, previous slot's first entry,
  current slot's first entry, 0)``; the vertex shader interpolates previous -> current.

Logic time: frame ``f`` shows ``interpolate(state k - 1, state k, alpha)`` with
``(k, alpha) = logic_tick(f / 60 s, logic_hz)`` (rgraph.scene.animation); the logic rate is
``plan["logic_hz"]`` (default 60). A logic thread (``rgraph.vk.scene_frame``) writes states
with :meth:`SkinGPU.write_slot` and frames name them with :meth:`SkinGPU.show_slots` instead.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rgraph.scene.animation import LOGIC_HZ, logic_tick
from rgraph.scene.build import SceneData
from rgraph.scene.skinning import BONE_BYTES
from rgraph.vk.device import Device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.resources import HostBuffer

BINDING_SKIN_VERTICES, BINDING_BONES, BINDING_SKIN_FRAME = range(7, 10)  # after scene.glsl's Views (5), Meshes (6)
SKIN_VERTEX_BYTES = 8
SKIN_FRAME_BYTES = 16
SLOTS = 8  # >= 2 sets x 2 slots in flight + the published pair + the one being written
WORKERS = ("process", "thread")  # graph param skin.worker


class SkinGPU:
    """See the module docstring. ``rigid_bases``: (mesh, first vertex in the rigid vertex
    buffer) of every skinned mesh; ``rigid_vertices``: that buffer's vertex count."""

    def __init__(self, device: Device, data: SceneData, sets: int, rigid_bases: list[tuple[Any, int]],
                 rigid_vertices: int, logic_hz: float = LOGIC_HZ, threads: int = 1, worker: str = "process") -> None:
        from rgraph.vk.loader import vk

        v = vk()
        if worker not in WORKERS:
            raise ExecutionError(f"skin.worker must be one of {', '.join(WORKERS)}, not {worker!r}")
        self.data, self.sets, self.logic_hz = data, sets, float(logic_hz)
        self.threads = max(1, int(threads))  # a tick's characters split over this many threads (Animator.state)
        self.worker_mode = worker  # with a logic thread (use_logic)
        self.worker: Any = None  # rgraph.scene.skin_worker.SkinWorker (use_logic, skin.worker=process)
        self.meshes = list(rigid_bases)
        self.bones = data.bone_count
        self.slots = max(SLOTS, 2 * sets + 3)
        self._buffers: list[HostBuffer] = []
        storage, uniform = v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, v.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT
        active = self.bones > 0
        self.vertex_bytes = rigid_vertices * SKIN_VERTEX_BYTES if active else 16
        self.vertices = self._buffer(device, self.vertex_bytes, storage)
        if active:
            table = np.zeros((rigid_vertices, 2), dtype=np.uint32)
            for mesh, base in rigid_bases:
                rig = mesh.animator.rig
                rows = slice(base, base + mesh.data.vertex_count)
                table[rows, 0] = rig.joints.astype(np.uint32) @ (1 << np.arange(0, 32, 8, dtype=np.uint32))
                table[rows, 1] = rig.weights.astype(np.uint32) @ (1 << np.arange(0, 32, 8, dtype=np.uint32))
            self.vertices.write(table.tobytes())
        header = self._header(data)
        self.header = len(header)  # entries before the first slot
        self.bones_bytes = max((self.header + self.slots * self.bones) * BONE_BYTES, 16)
        self.ring = self._buffer(device, self.bones_bytes, storage)
        self.ring.write(header.tobytes())
        self._ring_bytes = np.frombuffer(self.ring.mapped, dtype=np.uint8, count=self.bones_bytes)
        self.frames = [self._buffer(device, SKIN_FRAME_BYTES, uniform) for _ in range(sets)]
        self.frame_words = []  # per set: (float *, uint32_t *) cffi pointers to its SkinFrame
        for buf in self.frames:
            buf.write(bytes(SKIN_FRAME_BYTES))
            raw = v.ffi.from_buffer(buf.mapped)
            self.frame_words.append((v.ffi.cast("float *", raw), v.ffi.cast("uint32_t *", raw)))
        self._slot_tick: list[int | None] = [None] * self.slots
        self.in_use: list[tuple[int, int]] = [(-1, -1)] * sets  # slots each set's frame reads
        self._states: dict[int, np.ndarray] = {}

    @staticmethod
    def _header(data: SceneData) -> np.ndarray:
        """(entries, 4) uint32: per scene mesh its heads' first entry, then every skinned mesh's heads."""
        if not data.bone_count:
            return np.zeros((0, 4), dtype=np.uint32)
        table = np.zeros((len(data.meshes), 4), dtype=np.uint32)
        heads, entry = [], len(data.meshes)
        for k, mesh in enumerate(data.meshes):
            if mesh.animator is not None:
                h = mesh.animator.rig.skeleton.heads.astype(np.float32)
                table[k, 0] = entry
                heads.append(np.concatenate([h, np.zeros((len(h), 1), np.float32)], axis=1).view(np.uint32))
                entry += len(h)
        return np.concatenate([table, *heads])

    def _buffer(self, device: Device, size: int, usage: int) -> HostBuffer:
        buf = HostBuffer.create(device, size, usage)
        self._buffers.append(buf)
        return buf

    @property
    def active(self) -> bool:
        return self.bones > 0

    def descriptors(self) -> list[tuple[int, str, Any, int]]:
        """(binding, kind, buffer, range) for SceneGPU's descriptor writes."""
        return [(BINDING_SKIN_VERTICES, "storage", self.vertices, self.vertex_bytes),
                (BINDING_BONES, "storage", self.ring, self.bones_bytes)]

    def frame_descriptor(self, frame_set: int) -> tuple[int, str, Any, int]:
        return (BINDING_SKIN_FRAME, "uniform", self.frames[frame_set], SKIN_FRAME_BYTES)

    def state(self, tick: int) -> np.ndarray:
        """Logic state ``tick``: every skinned mesh's packed bones, concatenated (cached: two)."""
        got = self._states.get(tick)
        if got is None:
            parts = [m.animator.state(tick, self.logic_hz, self.threads).reshape(-1, 8) for m in self.data.skinned]
            got = np.concatenate(parts) if len(parts) > 1 else parts[0]
            self._states = {k: s for k, s in self._states.items() if k >= tick - 1}
            self._states[tick] = got
        return got

    def use_logic(self, hz: float) -> None:
        """States come at ``hz`` from a logic thread from now on; with ``skin.worker=process``
        a worker process evaluates them (started here, once)."""
        self.logic_hz = float(hz)
        if self.worker is not None and self.worker.hz != self.logic_hz:
            self.worker.close()
            self.worker = None
        if self.active and self.worker_mode == "process" and self.worker is None:
            from rgraph.scene.skin_worker import SkinWorker, SkinWorkerError

            try:
                self.worker = SkinWorker([m.animator for m in self.data.skinned], self.logic_hz, self.threads)
            except (OSError, SkinWorkerError) as exc:
                raise ExecutionError(f"skinning worker process: {exc}") from None

    def logic_stats(self) -> dict[str, Any]:
        """How the logic ticks' states were evaluated (the run's ``logic`` timings)."""
        if self.worker is not None:
            return self.worker.stats()
        return {"worker": "thread", "threads": self.threads}

    def _packed(self, tick: int) -> np.ndarray:
        """State ``tick`` as bytes: the worker's shared buffer, or evaluated here."""
        if self.worker is not None:
            return self.worker.fetch(tick)
        return np.ascontiguousarray(self.state(tick)).reshape(-1).view(np.uint8)

    def _write(self, slot: int, tick: int) -> None:
        """State ``tick`` into ring slot ``slot``: one NumPy copy, which releases the GIL while
        it runs (4 MiB for 1,024 x 256 bones: the render thread is not held up meanwhile)."""
        start = (self.header + slot * self.bones) * BONE_BYTES
        np.copyto(self._ring_bytes[start:start + self.bones * BONE_BYTES], self._packed(tick))
        self._slot_tick[slot] = tick

    def _slot_of(self, tick: int, frame_set: int, keep: int) -> int:
        if tick in self._slot_tick:
            return self._slot_tick.index(tick)
        busy = {s for k, held in enumerate(self.in_use) if k != frame_set for s in held} | {keep}
        slot = next(s for s in range(self.slots) if s not in busy)
        self._write(slot, tick)
        return slot

    def write_slot(self, tick: int, lock: Any, published: Any) -> int:
        """The logic thread's tick: state ``tick`` packed and written into a slot that no
        frame set reads (``in_use``) and ``published()`` (the slots of the states a frame may
        still take) does not name, chosen under ``lock``; its index."""
        with lock:
            busy = {*published(), *(x for pair in self.in_use for x in pair)}
            slot = next(s for s in range(self.slots) if s not in busy)
        self._slot_tick[slot] = None  # the state being written is no state yet
        self._write(slot, tick)
        return slot

    def show(self, frame_set: int, previous: int, current: int, alpha: float) -> None:
        """Frame set ``frame_set`` (its last frame finished) draws logic states ``previous`` ->
        ``current`` at ``alpha`` in [0, 1] (written into slots here when they are not yet)."""
        if not self.active:
            return
        a = self._slot_of(previous, frame_set, -1)
        b = self._slot_of(current, frame_set, a)
        self.in_use[frame_set] = (a, b)
        self.show_slots(frame_set, a, b, alpha)

    def show_slots(self, frame_set: int, a: int, b: int, alpha: float) -> None:
        """Frame set ``frame_set`` mixes ring slots ``a`` -> ``b`` at ``alpha`` (the SkinFrame
        uniform, written in place: 12 bytes)."""
        f, u = self.frame_words[frame_set]
        f[0] = min(max(alpha, 0.0), 1.0)
        u[1] = self.header + a * self.bones
        u[2] = self.header + b * self.bones

    def update(self, seconds: float, frame_set: int) -> None:
        """The frame at render time ``seconds``: states k - 1 -> k at alpha (module docstring)."""
        tick, alpha = logic_tick(seconds, self.logic_hz)
        self.show(frame_set, tick - 1, tick, alpha)

    def destroy(self) -> None:
        if self.worker is not None:
            self.worker.close()
            self.worker = None
        for buf in reversed(self._buffers):
            buf.destroy()
        self._buffers = []
