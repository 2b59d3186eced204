"""CPU deformation of a deformable mesh, every frame: breathing plus a pressing instrument.

Object space, float64. Breathing scales the mesh radially around its +Y axis; a Gaussian
dent (an instrument pressing on the skin) deepens and relaxes at the front (+Z) of the mesh
below the middle. Normals are recomputed from the deformed faces every frame (area
weighted, zero-area faces ignored, degenerate vertices fall back to their rest normal): they
are always unit length and never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgraph.scene.shapes import MeshData, vertex_normals

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

    def __post_init__(self) -> None:
        p = self.rest.positions
        radial = np.hypot(p[:, 0], p[:, 2])
        self._radius = float(radial.max()) if len(p) else 1.0
        lo, hi = self.rest.bounds() if len(p) else (np.zeros(3), np.zeros(3))
        target = np.array([0.0, lo[1] + 0.35 * (hi[1] - lo[1]), self._radius])
        # the press centre: the surface vertex nearest the front point below the middle
        self._centre = p[int(np.argmin(((p - target) ** 2).sum(axis=1)))].copy() if len(p) else target

    @property
    def max_displacement(self) -> float:
        """An upper bound of how far any vertex moves (for bounds)."""
        return self._radius * (self.breath_amplitude + 0.1 * self.press_depth)

    def positions(self, seconds: float) -> np.ndarray:
        p = self.rest.positions.copy()
        breath = 1.0 + self.breath_amplitude * np.sin(2.0 * np.pi * seconds / self.breath_period)
        p[:, 0] *= breath
        p[:, 2] *= breath
        press = 0.5 - 0.5 * np.cos(2.0 * np.pi * seconds / self.press_period)
        d2 = ((self.rest.positions - self._centre) ** 2).sum(axis=1)
        sigma = self.press_width * self._radius
        dent = 0.1 * self.press_depth * self._radius * press * np.exp(-d2 / (2.0 * sigma * sigma))
        return p - dent[:, None] * self.rest.normals

    def at(self, seconds: float) -> MeshData:
        pos = self.positions(seconds)
        idx = self.rest.indices.astype(np.int64)
        return MeshData(pos, vertex_normals(pos, idx, fallback=self.rest.normals), self.rest.indices)

    def at_frame(self, frame: int) -> MeshData:
        return self.at(frame * FRAME_SECONDS)
