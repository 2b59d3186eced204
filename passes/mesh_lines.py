"""``mesh_lines``: every mesh of the scene as a LINE_LIST with its own vertex buffer(s).

The pass of the allocator experiment (docs/allocator.md). Meshes come from the scene file
(``plan["scene_source"]``): each grid cell of a ``shape: segments`` mesh is one helix of
``params.segments`` line segments (``radius``, ``height``, ``turns``); ``deformable: true``
meshes are deformable. Graph params override (0 or negative = as in the scene):
``alloc.meshes`` (N meshes sampled evenly from the scene's cells, stacked in layers when N is
larger), ``alloc.segments``, ``alloc.deformable_fraction`` (spread evenly over the meshes).

Memory (``rgraph.vk.mesh_pool.MeshPool``, block size ``alloc.block_mib`` MiB, 0 = one
VkDeviceMemory per buffer): rigid meshes get one device-local buffer filled once through a
staging buffer; deformable ones one host-visible coherent buffer per frame-in-flight set of
capacity size x ``alloc.load_factor``, rewritten by the CPU in ``update`` (a sine wobble in x
of every deformable mesh: one float per vertex per frame, see ``_Wobble``); ``alloc.dynamic_memory:
device_local`` puts them in device-local host-visible memory (resizable BAR) where there is some. Recording: one ``vkCmdBindVertexBuffers`` and one ``vkCmdDraw`` per
mesh, in mesh order (per frame-in-flight set, recorded once).

Figures (``MeshLines.last_report``, and the JSON file ``alloc.report`` when set): pool
statistics, ``load_ms`` (wall clock from pool creation through allocation, binding, uploads
and the first fill of dynamic buffers), ``geometry_ms`` and ``wobble_setup_ms`` (NumPy, not
part of load_ms), ``record_ms`` (both sets), per-frame ``update_ms`` (median).
"""

from __future__ import annotations

import json
import math
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.mesh_pool import MIB, AllocationLimitError, MeshPool, PoolBuffer
from rgraph.vk.passkit import VertexInput

DEFAULT_SHAPE = {"segments": 100, "radius": 0.3, "height": 0.8, "turns": 4.0}
WOBBLE_AMPLITUDE = 0.25  # of the helix radius
BLOCK_MIB_CHOICES = (0, 4, 16, 64, 256)


# ===================================================================== layout (pure)
@dataclass
class MeshLayout:
    """Per-mesh placement and shape: arrays of length N."""

    positions: np.ndarray  # (N, 3) float64, the helix's base centre
    segments: np.ndarray  # (N,) int
    radius: np.ndarray  # (N,) float
    height: np.ndarray
    turns: np.ndarray
    phase: np.ndarray  # (N,) radians
    deformable: np.ndarray  # (N,) bool

    def __len__(self) -> int:
        return len(self.segments)

    def vertex_count(self, i: int) -> int:
        return 2 * int(self.segments[i])


def _scene_cells(scene: Any) -> list[tuple[tuple[float, float, float], dict, bool, int]]:
    """(position, shape params, deformable, seed) for every grid cell of every segments mesh."""
    cells = []
    for mesh in scene.meshes:
        if mesh.shape != "segments":
            continue
        shape = {**DEFAULT_SHAPE, **{k: v for k, v in mesh.params.items() if k in DEFAULT_SHAPE}}
        grid = mesh.instances.grid if mesh.instances else [1, 1, 1]
        spacing = mesh.instances.spacing if mesh.instances else 0.0
        px, py, pz = (float(c) for c in mesh.position)
        for ix in range(grid[0]):
            for iy in range(grid[1]):
                for iz in range(grid[2]):
                    cells.append(((px + ix * spacing, py + iy * spacing, pz + iz * spacing), shape,
                                  mesh.deformable, mesh.seed))
    return cells


def build_layout(scene: Any | None, meshes: int = 0, segments: int = 0, deformable_fraction: float = -1.0,
                 ) -> MeshLayout:
    """The meshes to draw: the scene's segments cells, then the param overrides (see module doc)."""
    cells = _scene_cells(scene) if scene is not None else []
    if not cells:  # no scene: a square grid of default helices, 10% deformable
        n = meshes if meshes > 0 else 10_000
        side = math.ceil(math.sqrt(n))
        cells = [((i % side - side / 2, 0.0, i // side - side / 2), DEFAULT_SHAPE, False, 0) for i in range(n)]
        if deformable_fraction < 0:
            deformable_fraction = 0.1
    total = len(cells)
    n = meshes if meshes > 0 else total
    idx = np.arange(n)
    pick = np.minimum((idx * total) // n, total - 1) if n <= total else idx % total
    layer = idx // total  # meshes beyond the scene's cells are stacked above it
    positions = np.array([cells[k][0] for k in pick], dtype=np.float64).reshape(n, 3)
    positions[:, 1] += layer * 1.5 * max(float(c[1]["height"]) for c in cells)
    shape = [cells[k][1] for k in pick]
    seg = np.array([segments if segments > 0 else int(s["segments"]) for s in shape], dtype=np.int64)
    if np.any(seg < 1):
        raise ExecutionError("mesh_lines: segments must be >= 1")
    if deformable_fraction >= 0:
        f = min(float(deformable_fraction), 1.0)
        deformable = np.floor((idx + 1) * f) > np.floor(idx * f)
    else:
        deformable = np.array([cells[k][2] for k in pick], dtype=bool)
    seeds = np.array([cells[k][3] for k in pick], dtype=np.int64)
    phase = (np.random.default_rng(0).random(n) + seeds * 0.618) * 2 * math.pi
    return MeshLayout(positions, seg, np.array([float(s["radius"]) for s in shape]),
                      np.array([float(s["height"]) for s in shape]), np.array([float(s["turns"]) for s in shape]),
                      phase % (2 * math.pi), deformable.astype(bool))


def helix_vertices(layout: MeshLayout, indices: np.ndarray, origin=(0.0, 0.0, 0.0)) -> list[np.ndarray]:
    """LINE_LIST vertices (2 x segments, 4) float32 of each mesh in ``indices``: xyz relative
    to ``origin`` (the pass gives the camera position: float32 keeps its precision far from
    the world origin) and the colour key (w: hue in [0, 1), +1 for deformable meshes).
    Vectorised per segment count."""
    ox, oy, oz = (float(c) for c in origin)
    out: list[np.ndarray | None] = [None] * len(indices)
    indices = np.asarray(indices)
    seg_of = layout.segments[indices]
    for s in np.unique(seg_of):
        where = np.nonzero(seg_of == s)[0]
        m = indices[where]
        t = np.linspace(0.0, 1.0, int(s) + 1)[None, :]  # (1, s+1)
        angle = 2 * math.pi * layout.turns[m, None] * t + layout.phase[m, None]
        points = np.empty((len(m), int(s) + 1, 4), dtype=np.float64)
        points[..., 0] = (layout.positions[m, 0, None] - ox) + layout.radius[m, None] * np.cos(angle)
        points[..., 1] = (layout.positions[m, 1, None] - oy) + layout.height[m, None] * t
        points[..., 2] = (layout.positions[m, 2, None] - oz) + layout.radius[m, None] * np.sin(angle)
        points[..., 3] = (m[:, None] * 0.618034) % 1.0 + layout.deformable[m, None]
        lines = np.empty((len(m), 2 * int(s), 4), dtype=np.float32)
        lines[:, 0::2] = points[:, :-1]
        lines[:, 1::2] = points[:, 1:]
        for k, w in enumerate(where):
            out[w] = lines[k]
    return out  # type: ignore[return-value]


def camera_position(camera: Any | None) -> np.ndarray:
    return np.array(camera.position if camera else (0.0, 55.0, 80.0), dtype=np.float64)


def view_projection(camera: Any | None, aspect: float, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Row-major view-projection of positions relative to ``origin``: look-at view (a view
    direction parallel to ``up`` picks another reference axis), reversed-Z infinite
    perspective, Vulkan y-down clip."""
    from rgraph.scene.camera import orthonormal_basis

    eye = camera_position(camera) - np.asarray(origin, dtype=np.float64)
    target = np.array(camera.look_at if camera else (0.0, 0.0, 0.0), dtype=np.float64) - np.asarray(origin)
    up = np.array(camera.up if camera else (0.0, 1.0, 0.0), dtype=np.float64)
    fov_y = math.radians(camera.fov_y if camera else 50.0)
    near = float(camera.near if camera else 0.1)
    f = target - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    if np.linalg.norm(r) <= 1e-3 * np.linalg.norm(up):  # looking along up: no cross product
        r, _, _ = orthonormal_basis(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = r, u, -f
    view[:3, 3] = -view[:3, :3] @ eye
    g = 1.0 / math.tan(fov_y / 2)
    proj = np.zeros((4, 4))
    proj[0, 0] = g / aspect
    proj[1, 1] = -g
    proj[2, 3] = near  # depth = near / -z_view: 1 at the near plane, 0 at infinity
    proj[3, 2] = -1.0
    return proj @ view


# ===================================================================== the pass
class _Wobble:
    """Per-frame CPU deformation of the deformable meshes, written through the pool's mappings.

    Only x moves, so a frame writes one float per vertex. Writes go through strided NumPy views
    of the mapped memory, one per *run*: meshes consecutive in mesh order, of one vertex count,
    in one memory object at a constant row stride (what a block holds when buffers of one
    capacity are placed one after the other). A dedicated allocation is a run of one mesh.
    """

    def __init__(self, base: list[np.ndarray], layout: MeshLayout, meshes: np.ndarray) -> None:
        self.counts = np.array([len(b) for b in base], dtype=np.int64)
        self.starts = np.concatenate([[0], np.cumsum(self.counts)[:-1]]).astype(np.int64)
        self.base = np.concatenate(base) if base else np.zeros((0, 4), np.float32)
        along = np.concatenate([np.linspace(0, 1, c) for c in self.counts]) if base else np.zeros(0)
        self.phase = (along * 3 * math.pi + np.repeat(layout.phase[meshes], self.counts)).astype(np.float32)
        self.amplitude = np.repeat(layout.radius[meshes] * WOBBLE_AMPLITUDE, self.counts).astype(np.float32)
        self.runs: dict[int, list[tuple[np.ndarray, np.ndarray, slice]]] = {}  # set -> (full view, x view, src)

    def bind(self, frame_set: int, pool: Any, buffers: list[PoolBuffer]) -> None:
        """Cut this set's buffers (in mesh order) into runs and make their views."""
        runs = []
        k = 0
        while k < len(buffers):
            block, first, count = buffers[k].allocation.block, buffers[k].first_row, int(self.counts[k])
            stride, end = count, k + 1
            if end < len(buffers) and buffers[end].allocation.block is block \
                    and buffers[end].first_row - first >= count:
                stride = buffers[end].first_row - first
                while (end < len(buffers) and buffers[end].allocation.block is block
                       and int(self.counts[end]) == count
                       and buffers[end].first_row == first + (end - k) * stride):
                    end += 1
            rows = pool.rows(buffers[k])
            n = end - k
            full = np.lib.stride_tricks.as_strided(rows[first:], shape=(n, count, 4),
                                                   strides=(stride * rows.strides[0], *rows.strides))
            runs.append((full, full[..., 0], slice(int(self.starts[k]), int(self.starts[k]) + n * count)))
            k = end
        self.runs[frame_set] = runs

    def x(self, frame: int) -> np.ndarray:
        """The x coordinate of every deformable vertex at ``frame`` (float32, mesh order)."""
        return self.base[:, 0] + self.amplitude * np.sin(self.phase + np.float32(frame * 0.15))

    def fill(self, frame_set: int) -> None:
        """Write whole vertices (the first fill)."""
        for full, _x, src in self.runs[frame_set]:
            full[...] = self.base[src].reshape(full.shape)

    def write(self, frame: int, frame_set: int) -> None:
        x = self.x(frame)
        for _full, xs, src in self.runs[frame_set]:
            xs[...] = x[src].reshape(xs.shape)


@register("mesh_lines")
class MeshLines(PassImpl):
    """See the module docstring."""
    param_schema = {
        "alloc.block_mib": Param(int, choices=(0, 4, 16, 64, 256)), "alloc.meshes": Param(int, 0, 1 << 20),
        "alloc.segments": Param(int, 0, 1 << 20), "alloc.deformable_fraction": Param(float, -1, 1),
        "alloc.load_factor": Param(float, 1, 64), "alloc.dynamic_memory": Param(str, choices=("host", "device_local")),
        "alloc.max_allocations": Param(int, 0, 1 << 32), "alloc.over_limit": Param(str, choices=("error", "try")),
        "alloc.report": Param(str, output=True),
    }

    clear_values: ClassVar[dict[str, Any]] = {"color": (0.02, 0.02, 0.03, 1.0), "depth": 0.0}
    #: The figures of the most recent instance (the benchmark reads them in-process).
    last_report: ClassVar[dict[str, Any]] = {}

    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        p = setup.param
        self.block_mib = int(p("alloc.block_mib", 64))
        if self.block_mib < 0:
            raise ExecutionError(f"mesh_lines: alloc.block_mib must be >= 0 (one of {BLOCK_MIB_CHOICES})")
        self.load_factor = float(p("alloc.load_factor", 1.5))
        if self.load_factor < 1.0:
            raise ExecutionError("mesh_lines: alloc.load_factor must be >= 1")
        over = str(p("alloc.over_limit", "error"))
        if over not in ("error", "try"):
            raise ExecutionError(f"mesh_lines: alloc.over_limit must be 'error' or 'try', not {over!r}")
        self.dynamic_memory = str(p("alloc.dynamic_memory", "host"))
        if self.dynamic_memory not in ("host", "device_local"):
            raise ExecutionError(f"mesh_lines: alloc.dynamic_memory must be 'host' or 'device_local', "
                                 f"not {self.dynamic_memory!r}")
        self.report_path = str(p("alloc.report", "") or "")
        scene_path = setup.plan.get("scene_source")
        scene = None
        if scene_path:
            from rgraph.spec.scene import load_scene

            scene = load_scene(scene_path).model
        t0 = time.perf_counter()
        self.layout = build_layout(scene, int(p("alloc.meshes", 0)), int(p("alloc.segments", 0)),
                                   float(p("alloc.deformable_fraction", -1.0)))
        order = np.arange(len(self.layout))
        self.rigid = order[~self.layout.deformable]
        self.deformable = order[self.layout.deformable]
        camera = scene.camera if scene else None
        eye = camera_position(camera)  # camera-relative vertices (scenes far from the origin)
        rigid_vertices = helix_vertices(self.layout, self.rigid, eye)
        deform_vertices = helix_vertices(self.layout, self.deformable, eye)
        geometry_ms = (time.perf_counter() - t0) * 1e3
        w, h = setup.extent
        self.view_proj = view_projection(camera, w / h, eye).T.astype(np.float32).tobytes()
        self.pipeline = setup.graphics_pipeline(
            "lines/mesh.vert", "lines/mesh.frag", [], push_constant_bytes=64,
            vertex_input=VertexInput(16, [(0, "r32g32b32a32_sfloat", 0)]), topology="LINE_LIST",
            depth_test=True, depth_write=True)
        self.sets = setup.sets
        max_alloc = int(p("alloc.max_allocations", 0)) or None
        self.report: dict[str, Any] = {
            "block_mib": self.block_mib, "meshes": len(self.layout), "rigid": len(self.rigid),
            "deformable": len(self.deformable), "segments": int(self.layout.segments.max(initial=0)),
            "load_factor": self.load_factor, "sets": self.sets, "dynamic_memory": self.dynamic_memory, "device": setup.device.name,
            "geometry_ms": geometry_ms, "vertex_bytes": int(sum(v.nbytes for v in rigid_vertices)
                                                             + sum(v.nbytes for v in deform_vertices)),
        }
        MeshLines.last_report = self.report
        self.pool: MeshPool | None = None
        self.frame_times: list[float] = []
        try:
            self._load(setup, rigid_vertices, deform_vertices, max_alloc, over == "error")
        except ExecutionError as exc:
            if self.pool is not None:
                self.report.update(self.pool.stats())
                self.pool.destroy()
                self.pool = None
            setup.destroy()  # the runtime only tears down passes that finished construction
            self.report["error"] = str(exc)
            if isinstance(exc, AllocationLimitError):
                self.report["allocations_needed"] = exc.needed
                self.report["limit"] = exc.limit
            self._write_report()
            raise

    def _load(self, setup: Any, rigid_vertices: list[np.ndarray], deform_vertices: list[np.ndarray],
              max_alloc: int | None, enforce: bool) -> None:
        t0 = time.perf_counter()
        pool = self.pool = MeshPool(setup.device, self.block_mib * MIB, max_allocations=max_alloc,
                                    enforce_limit=enforce, dynamic_device_local=self.dynamic_memory == "device_local")
        if self.block_mib == 0:  # say it before allocating thousands of objects
            needed = len(rigid_vertices) + self.sets * len(deform_vertices) + (1 if rigid_vertices else 0)
            self.report["allocations_needed"] = needed
            pool.allocator.check_room(needed, f"block size 0 (one VkDeviceMemory per buffer, on "
                                              f"{setup.device.name}): ")
        self.rigid_buffers = [pool.create_buffer(v.nbytes) for v in rigid_vertices]
        self.deform_buffers = [[pool.create_buffer(v.nbytes, math.ceil(v.nbytes * self.load_factor / 16) * 16,
                                                   dynamic=True) for v in deform_vertices]
                               for _ in range(self.sets)]
        pool.upload(list(zip(self.rigid_buffers, rigid_vertices, strict=True)),
                    setup.device.queues["graphics"], setup.device.families["graphics"])
        loaded = time.perf_counter() - t0
        t1 = time.perf_counter()  # NumPy index tables of the per-frame writes: not load time
        self.wobble = _Wobble(deform_vertices, self.layout, self.deformable)
        for s in range(self.sets):
            self.wobble.bind(s, pool, self.deform_buffers[s])
        t2 = time.perf_counter()
        for s in range(self.sets):  # the first fill of the dynamic buffers
            self.wobble.fill(s)
            self.wobble.write(0, s)
        self.report["load_ms"] = (loaded + time.perf_counter() - t2) * 1e3
        self.report["wobble_setup_ms"] = (t2 - t1) * 1e3
        self.report.update(pool.stats())
        # draw order: mesh order; per set the VkBuffer of each mesh
        rigid_at = {int(m): k for k, m in enumerate(self.rigid)}
        deform_at = {int(m): k for k, m in enumerate(self.deformable)}
        self.draws: list[list[tuple[Any, int]]] = []
        for s in range(self.sets):
            draws = []
            for m in range(len(self.layout)):
                buf = (self.rigid_buffers[rigid_at[m]] if m in rigid_at
                       else self.deform_buffers[s][deform_at[m]])
                draws.append((buf.handle, self.layout.vertex_count(m)))
            self.draws.append(draws)
        self.record_ms = 0.0

    def update(self, frame: int, frame_set: int) -> None:
        if not len(self.deformable):
            return
        t0 = time.perf_counter()
        self.wobble.write(frame, frame_set)
        self.frame_times.append((time.perf_counter() - t0) * 1e3)

    def record(self, rec: Any, frame_set: int) -> None:
        t0 = time.perf_counter()
        rec.bind(self.pipeline)
        rec.push(self.pipeline, self.view_proj)
        for handle, count in self.draws[frame_set]:
            rec.bind_vertex_buffers([handle])
            rec.draw(count)
        self.record_ms += (time.perf_counter() - t0) * 1e3
        self.report["record_ms"] = self.record_ms
        self.report["draws_per_frame"] = len(self.draws[frame_set])
        self.report["binds_per_frame"] = len(self.draws[frame_set])

    def destroy(self) -> None:
        if self.frame_times:
            self.report["update_ms"] = statistics.median(self.frame_times)
            self.report["update_frames"] = len(self.frame_times)
        if self.pool is not None:
            stats = self.pool.stats()  # steady-state figures, before the teardown zeroes them
            self.pool.destroy()
            after = self.pool.stats()
            self.report.update({k: stats[k] for k in ("allocations", "blocks", "dedicated", "allocated_bytes",
                                                      "bound_bytes", "used_bytes")})
            self.report["destroy_ms"] = after["destroy_ms"]
            self.report["vk_free_ms"] = after["vk_free_ms"]
            self.report["allocations_after_destroy"] = after["allocations"]
            self.pool = None
        self._write_report()

    def _write_report(self) -> None:
        if self.report_path:
            Path(self.report_path).write_text(json.dumps(self.report, indent=1, sort_keys=True) + "\n")
