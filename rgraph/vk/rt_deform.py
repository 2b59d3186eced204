"""Deformable meshes in ray tracing plans: each frame's deformed geometry, per frame-in-flight set.

When an accel over the scene is built every frame (a persistent accel the plan marks
``refit``, or a per-frame one) and the scene has deformable meshes, ``rgraph.vk.accel.AccelSet``
owns one ``DeformedTables``: per set, the positions and normals tables in the layout of the
passes' scene tables (``passes.raytrace_standalone.pack_tables``: every mesh's object-space
float32 vertices, mesh after mesh). Static meshes are written once.

- Positions: host-visible, coherent (device-local where a memory type is both, e.g. resizable
  BAR). ``update(frame, set)`` writes the deformable meshes' at the frame's scene time
  (``Deformer.write_positions``: what the raster path gets). Readers of set ``s``: that frame's
  BLAS builds/refits (vertex input by device address), the hit/shade passes' and the compute
  visibility buffer's table reads, the normals pass. The frame loop writes set ``s`` after
  waiting on its fences (its previous frame, everything that read the buffer, has finished) and
  before the frame's ``vkQueueSubmit2``, which makes earlier host writes to coherent memory
  visible to every command in it (the host -> device memory domain operation): no barrier.
- Normals: device-local, written on the GPU by the raster path's smoothing pass in every frame
  build of an accel built from this geometry (``rgraph.vk.rt_normals``, with its barriers);
  read by the hit/shade passes. Their float64 NumPy reference: ``Deformer.traced``.

Skinned meshes stay in their rest pose.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rgraph.vk.device import Device

STORAGE_BUFFER = 0x20


def has_deformable(plan: dict) -> bool:
    from rgraph.vk.rt_scene import scene_data

    return any(m.deformer is not None for m in scene_data(plan).meshes)


class DeformedTables:
    """See the module docstring. ``sets``: frame-in-flight sets."""

    def __init__(self, device: Device, plan: dict, sets: int) -> None:
        from rgraph.vk.accel import INPUT_USAGE, AddressBuffer
        from rgraph.vk.rt_normals import NormalsGPU
        from rgraph.vk.rt_scene import scene_data

        self.data = scene_data(plan)
        self.sets = sets
        meshes = self.data.meshes
        self.first_vertex = np.concatenate([[0], np.cumsum([m.data.vertex_count for m in meshes])]).astype(np.int64)
        vertices = int(self.first_vertex[-1])
        positions = np.concatenate([m.data.positions for m in meshes]).astype(np.float32)
        normals = np.concatenate([m.data.normals for m in meshes]).astype(np.float32)
        self.deformable = [k for k, m in enumerate(meshes) if m.deformer is not None]
        self.positions: list[Any] = []  # per set: AddressBuffer (BLAS input, storage)
        self._views: list[np.ndarray] = []  # per set: (vertices, 3) float32 of the mapped memory
        self.normals: Any = None
        try:
            for _ in range(sets):
                # every hit and the visibility buffer read them: device-local where the host sees such memory
                pos = AddressBuffer.create(device, positions.nbytes, INPUT_USAGE | STORAGE_BUFFER, device_local=True)
                self.positions.append(pos)
                pos.host.write(positions.tobytes())
                self._views.append(np.frombuffer(pos.host.mapped, dtype=np.float32, count=3 * vertices).reshape(-1, 3))
            self.normals = NormalsGPU(device, self, self.position_buffers(), normals.tobytes())
        except BaseException:
            self.destroy()
            raise
        self.frame_of: list[int | None] = [None] * sets  # per set: the content frame its geometry shows
        self._writers = [(meshes[k].deformer, int(self.first_vertex[k]), int(self.first_vertex[k + 1]))
                         for k in self.deformable]  # (deformer, first vertex, end): the per-frame writes

    def update(self, frame: int, frame_set: int) -> None:
        """Set ``frame_set`` shows the deformable meshes at content frame ``frame``'s scene time
        (its previous frame has finished; called before the frame's submits). Once per frame."""
        if self.frame_of[frame_set] == frame:
            return
        seconds = self.data.seconds(frame)
        view = self._views[frame_set]
        for deformer, lo, hi in self._writers:
            deformer.write_positions(seconds, view[lo:hi])  # mapped memory: only written
        self.frame_of[frame_set] = frame

    def record_normals(self, cb: Any, frame_set: int) -> None:
        """Set ``frame_set``'s normals from its positions (in a build of an accel of this geometry)."""
        self.normals.record(cb, frame_set)

    def is_deformable(self, mesh: int) -> bool:
        return mesh in self.deformable

    def vertex_address(self, mesh: int, frame_set: int) -> int:
        """Device address of mesh ``mesh``'s first position in set ``frame_set``'s buffer."""
        return self.positions[frame_set].address + 12 * int(self.first_vertex[mesh])

    def position_buffers(self) -> tuple[tuple[Any, int], ...]:
        """(VkBuffer, bytes) per set: the passes' positions table."""
        return tuple((b.host.handle, b.host.size) for b in self.positions)

    def normal_buffers(self) -> tuple[tuple[Any, int], ...]:
        return self.normals.normal_buffers()

    def destroy(self) -> None:
        self._views = []
        if self.normals is not None:
            self.normals.destroy()
            self.normals = None
        for b in self.positions:
            b.destroy()
        self.positions = []
