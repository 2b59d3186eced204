"""The study's two workloads for benchmarks/multi_gpu.py (issue 16): a per-pixel-heavy
full-screen pass (sort-first) and a procedural mesh of ``mg.triangles`` triangles (sort-last).

Importing this module registers their pass implementations.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

from rgraph.impl import Param, PassImpl, register
from rgraph.plan.devices import DRAWS

HERE = Path(__file__).resolve().parent
PIXELS = HERE / "pixels.yaml"
MESH = HERE / "mesh.yaml"


def grid(triangles: int, chunks: int) -> tuple[int, int]:
    """Columns x rows of quads per chunk: about ``triangles`` in all, whole rows (no gaps)."""
    quads = max(1, triangles // chunks // 2)
    columns = max(1, math.isqrt(quads * 4))  # strips are wide: a chunk spans the screen width
    return min(columns, quads), max(1, quads // min(columns, quads))


def mesh_triangles(triangles: int, chunks: int) -> int:
    """The triangles ``Mesh`` draws for ``mg.triangles``/``mg.chunks`` (whole rows)."""
    columns, rows = grid(triangles, chunks)
    return 2 * columns * rows * chunks


@register("multi_gpu_pixels")
class Pixels(PassImpl):
    """``mg.iterations`` Julia steps per pixel (``pixels.frag``)."""

    param_schema = {"mg.iterations": Param(int, 1, 1 << 20)}
    clear_values = {"color": (0.0, 0.0, 0.0, 1.0)}

    def __init__(self, setup):
        super().__init__(setup)
        iterations = int(setup.param("mg.iterations", 256))
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", str(HERE / "pixels.frag"), [],
                                                defines={"ITERATIONS": iterations})

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [])
        rec.draw(3)


def chunk_range(chunks: int, share: list[int] | None) -> tuple[int, int]:
    """The contiguous chunks ``[first, end)`` of ``share = [device, devices]`` (all without one):
    earlier devices get earlier chunks, so the composite's ties (device 0 wins) match one device's."""
    if not share:
        return 0, chunks
    d, n = int(share[0]), int(share[1])
    return d * chunks // n, (d + 1) * chunks // n


@register("multi_gpu_mesh")
class Mesh(PassImpl):
    """``mg.triangles`` procedural triangles in ``mg.chunks`` instanced chunks (``mesh.vert``)."""

    param_schema = {"mg.triangles": Param(int, 2, 1 << 34), "mg.chunks": Param(int, 1, 1 << 16)}
    clear_values = {"depth": 0.0, "color": (0.0, 0.0, 0.0, 1.0)}
    attachment_load = {"depth": "clear", "color": "clear"}

    def __init__(self, setup):
        super().__init__(setup)
        self.chunks = int(setup.param("mg.chunks", 64))
        total = int(setup.param("mg.triangles", 1_000_000))
        columns, rows = grid(total, self.chunks)
        self.per_chunk = 2 * columns * rows
        self.first, self.end = chunk_range(self.chunks, setup.param(DRAWS))
        self.push = struct.pack("<4i", self.per_chunk, self.chunks, columns, 0)
        self.pipeline = setup.graphics_pipeline(str(HERE / "mesh.vert"), str(HERE / "mesh.frag"), [],
                                                push_constant_bytes=16, depth_test=True, depth_write=True,
                                                depth_compare="GREATER")

    def record(self, rec, frame_set):
        if self.end <= self.first:
            return
        rec.bind(self.pipeline, [])
        rec.push(self.pipeline, self.push)
        rec.draw(3 * self.per_chunk, self.end - self.first, 0, self.first)
