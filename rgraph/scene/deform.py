"""CPU deformation of a deformable mesh, every frame: breathing plus a pressing instrument.

Object space, float64. Breathing scales the mesh radially around its +Y axis; a Gaussian
dent (an instrument pressing on the skin) deepens and relaxes at the front (+Z) of the mesh
below the middle. Normals and tangents follow the deformed faces (``rgraph.scene.smoothing``:
area weighted, smoothing groups across UV seams, zero-area faces ignored, degenerate vertices
fall back to their rest normal; always unit length, never NaN): on the GPU every frame
(``rgraph.vk.scene_deform``), here in float64 as the reference (``at``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgraph.scene.shapes import MeshData
from rgraph.scene.smoothing import SmoothingTopology, build_topology, normals_tangents, smooth_normals

FRAME_SECONDS = 1.0 / 60.0


@dataclass
class Deformer:
    rest: MeshData
    breath_amplitude: float = 0.04  # relative radial change
    breath_period: float = 4.0  # seconds
    press_depth: float = 0.35  # deepest press = 0.1 * press_depth * the mesh radius
    press_period: float = 1.7
    press_width: float = 0.25  # fraction of the mesh radius
    _radius: float = field(init=False, default=1.0)
    _centre: np.ndarray = field(init=False)
    # positions = basis^T (1, breath - 1, -depth): rest, its radial (x, z) part, the dent
    # direction (Gaussian falloff * rest normal); (3, 3n) float64 and float32
    _basis: np.ndarray = field(init=False, repr=False)
    _basis32: np.ndarray = field(init=False, repr=False)
    topology: SmoothingTopology = field(init=False, repr=False)
    _scratch: np.ndarray | None = field(init=False, default=None, repr=False)

    def __post_init__(self) -> None:
        p = self.rest.positions
        radial = np.hypot(p[:, 0], p[:, 2])
        self._radius = float(radial.max()) if len(p) else 1.0
        lo, hi = self.rest.bounds() if len(p) else (np.zeros(3), np.zeros(3))
        target = np.array([0.0, lo[1] + 0.35 * (hi[1] - lo[1]), self._radius])
        # the press centre: the surface vertex nearest the front point below the middle
        self._centre = p[int(np.argmin(((p - target) ** 2).sum(axis=1)))].copy() if len(p) else target
        d2 = ((p - self._centre) ** 2).sum(axis=1)
        sigma = self.press_width * self._radius
        dent = np.exp(-d2 / (2.0 * sigma * sigma))[:, None] * self.rest.normals
        self._basis = np.stack([p.reshape(-1), (p * (1.0, 0.0, 1.0)).reshape(-1), dent.reshape(-1)])
        self._basis32 = self._basis.astype(np.float32)
        self.topology = build_topology(len(p), self.rest.indices, self.rest.smooth_group, p)

    @property
    def max_displacement(self) -> float:
        """An upper bound of how far any vertex moves (for bounds)."""
        return self._radius * (self.breath_amplitude + 0.1 * self.press_depth)

    def _coefficients(self, seconds: float) -> np.ndarray:
        breath = 1.0 + self.breath_amplitude * np.sin(2.0 * np.pi * seconds / self.breath_period)
        press = 0.5 - 0.5 * np.cos(2.0 * np.pi * seconds / self.press_period)
        return np.array([1.0, breath - 1.0, -0.1 * self.press_depth * self._radius * press])

    def positions(self, seconds: float) -> np.ndarray:
        """Deformed positions at ``seconds`` (n, 3) float64: the rest positions scaled radially
        by the breath, minus the dent along the rest normals."""
        return (self._coefficients(seconds) @ self._basis).reshape(-1, 3)

    def write_positions(self, seconds: float, out: np.ndarray) -> None:
        """``positions(seconds)`` in float32 into ``out`` ((n, 3) float32, C-contiguous: e.g.
        mapped memory) without allocating (the per-frame path; within about one float32 ulp of
        ``positions``): rest + c1 radial + c2 dent as single-threaded array operations on
        scratch arrays, not a BLAS product (whose thread pool would wake on the render thread
        every frame); the last one writes ``out``, which is only written, never read (mapped
        memory may be write-combined: reads from it are uncached). One writer at a time (the
        render thread, or the logic thread with ``--logic-hz``)."""
        if not out.flags.c_contiguous or out.dtype != np.float32 or out.size != self._basis32.shape[1]:
            raise ValueError("write_positions: out must be a C-contiguous (n, 3) float32 array")
        c = self._coefficients(seconds)
        basis = self._basis32  # rows: rest, radial, dent (flat, contiguous: fast NumPy loops)
        if self._scratch is None:
            self._scratch = np.empty((2, basis.shape[1]), dtype=np.float32)
        acc, term = self._scratch
        np.multiply(basis[1], np.float32(c[1]), out=acc)
        np.add(acc, basis[0], out=acc)  # c[0] is 1
        np.multiply(basis[2], np.float32(c[2]), out=term)
        np.add(acc, term, out=out.reshape(-1))  # out is only written

    def at(self, seconds: float) -> MeshData:
        """The deformed mesh with its reference normals (float64; ``tangents_at`` for tangents)."""
        pos = self.positions(seconds)
        normals, _tangents = normals_tangents(pos, self.rest.indices, self.topology, self.rest.normals,
                                              self.rest.uvs)
        return MeshData(pos, normals, self.rest.indices, self.rest.uvs, self.rest.smooth_group)

    def tangents_at(self, seconds: float) -> np.ndarray:
        """Reference tangents (n, 4) at ``seconds``: xyz unit, w the bitangent's handedness."""
        return normals_tangents(self.positions(seconds), self.rest.indices, self.topology, self.rest.normals,
                                self.rest.uvs)[1]

    def traced(self, seconds: float) -> tuple[np.ndarray, np.ndarray]:
        """The reference of the ray tracing geometry at ``seconds`` (``passes.rt_model.build_tables``;
        the GPU's: ``rgraph.vk.rt_deform``): the float32 positions ``write_positions`` gives the
        raster path and ray tracing, and their reference normals (float64, of those positions)."""
        pos = np.empty((self.rest.vertex_count, 3), dtype=np.float32)
        self.write_positions(seconds, pos)
        return pos, smooth_normals(pos, self.rest.indices, self.topology, self.rest.normals)

    def at_frame(self, frame: int) -> MeshData:
        return self.at(frame * FRAME_SECONDS)
