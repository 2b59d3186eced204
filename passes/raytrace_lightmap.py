"""The hybrid's light maps (graphs/rt_hybrid.yaml, ``shaders/rt/light_maps.glsl``): shadow
rays only where a cached light-space depth cannot decide.

- ``rt_light_maps`` (raytrace): per mapped light (the first :data:`MAPPED_LIGHTS`), one ray per
  texel from the light to the first surface, its distance stored in ``light_maps`` (r32f,
  6 layers per light: a point light's cube faces; a directional light's cascades, parallel
  rays from a plane outside the scene's bounds over the view frustum between two depths).
  Traced once per frame set (an indirect trace whose arguments are zero afterwards): the maps
  depend on the scene, its lights and the run's camera (the camera-relative world of the
  accel), not on the frame, like the accel built once at load. Scenes with deformable meshes
  (refitted every frame) and ``rt.light_maps: 0`` trace nothing and map no light.
- The shading passes that read ``light_maps`` (``light_map_bindings``) test each shadow ray
  first: every ray of the 2x2 texels around the point reaches the point's plane -> lit; all stop
  well before it -> in shadow; else the shadow ray is traced. Only where a texel is at most two
  pixel footprints wide at the point (``rt.light_map_guard``, default 2): an occluder (or a hole) the taps
  miss is narrower than a texel, so its shadow is narrower than two pixels there.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any

import numpy as np

from rgraph.impl import register
from rgraph.vk.passkit import Binding

from .raytrace_standalone import RayTracingImpl, deformed_tables
from .rt_model import MAX_LIGHTS, camera_basis

#: Lights with a map (6 layers each); the graph's ``light_maps`` layers are sized for them.
MAPPED_LIGHTS = 4
#: A directional light's cascades: one layer each (a point light's six are its cube faces).
CASCADES = 6
INFO_FLOATS = 64  # 16 vec4 per mapped light (shaders/rt/light_maps.glsl)


def mapped_lights(setup: Any, data) -> int:
    """Lights with a map: none without ``light_maps`` in the pass, with ``rt.light_maps`` 0,
    over deformable meshes (the maps would go stale) or past the image's layers."""
    if not setup.has("light_maps") or int(setup.param("rt.light_maps", 1)) == 0 or deformed_tables(setup) is not None:
        return 0
    layers = int(setup.resource_plan("light_maps").get("layers", 1))
    return min(len(data.lights), MAX_LIGHTS, MAPPED_LIGHTS, layers // 6)


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The 8 corners of the box [lo, hi]."""
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def scene_bounds(data) -> tuple[np.ndarray, np.ndarray]:
    """Camera-relative bounding box (min, max) of every instance of every mesh."""
    from rgraph.scene.camera import model_matrix

    cam, _basis, _tan = camera_basis(data)
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for mesh in data.meshes:
        if not len(mesh.positions) or not mesh.data.vertex_count:
            continue
        pos = np.asarray(mesh.data.positions, dtype=np.float64).reshape(-1, 3)
        corners = box_corners(pos.min(axis=0), pos.max(axis=0))
        linear = model_matrix(np.zeros(3), mesh.rotation, mesh.scale)[:3, :3]
        box = corners @ linear.T
        offsets = np.asarray(mesh.positions, dtype=np.float64).reshape(-1, 3) - cam
        lo = np.minimum(lo, box.min(axis=0) + offsets.min(axis=0))
        hi = np.maximum(hi, box.max(axis=0) + offsets.max(axis=0))
    if not np.all(np.isfinite(lo)):
        return np.zeros(3), np.zeros(3)
    return lo, hi


def light_basis(to_light: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(U, V, W) of a directional light: W the maps' ray direction (away from the light)."""
    w = -to_light / np.linalg.norm(to_light)
    helper = np.array([0.0, 1.0, 0.0]) if abs(w[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(w, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(w, u), w


@dataclass(frozen=True)
class View:
    """The camera of the maps' frame (camera-relative: at the origin)."""

    basis: np.ndarray  # rows right, up, forward
    tan_half: float    # of the vertical field of view
    aspect: float
    near: float


def slice_corners(view: View, d0: float, d1: float) -> np.ndarray:
    """The 8 corners of the view frustum between depths d0 and d1."""
    right, up, fwd = view.basis
    out = []
    for d in (d0, d1):
        for sx in (-1.0, 1.0):
            for sy in (-1.0, 1.0):
                out.append(d * (fwd + sx * view.tan_half * view.aspect * right + sy * view.tan_half * up))
    return np.array(out)


def cascade_depths(view: View, lo: np.ndarray, hi: np.ndarray) -> list[float]:
    """CASCADES + 1 depths from the near plane to the scene's farthest corner, in geometric
    steps (each cascade's texels then grow as the pixels' footprints do)."""
    far = max(float((box_corners(lo, hi) @ view.basis[2]).max()), 2.0 * view.near)
    return [view.near * (far / view.near) ** (k / CASCADES) for k in range(CASCADES + 1)]


def directional_frame(to_light: np.ndarray, lo: np.ndarray, hi: np.ndarray, size: tuple[int, int],
                      view: View | None = None) -> list[float]:
    """The 16 vec4 of a directional light's maps (shaders/rt/light_maps.glsl): (0, 0, 0, 0),
    (U, 0), (V, 0), (W, cascades), then per cascade (grid corner C0, du), (0, 0, 0, dv). Cascade k
    covers the view frustum between the k-th and (k+1)-th of ``cascade_depths`` (all of the scene's
    box without a view), clipped to the box, with two texels of margin; every grid's plane lies
    outside the box, so its rays see every occluder before the points they reach."""
    u, v, w = light_basis(to_light)
    box = box_corners(lo, hi)
    bu, bv, bw = box @ u, box @ v, box @ w
    extent = max(float(np.ptp(bu)), float(np.ptp(bv)), float(np.ptp(bw)), 1e-6)
    plane = float(bw.min()) - 0.01 * extent
    if view is None:
        regions = [box]
    else:
        depths = cascade_depths(view, lo, hi)
        regions = [slice_corners(view, depths[k], depths[k + 1]) for k in range(CASCADES)]
    rows = [0.0] * 4 + [*u, 0.0, *v, 0.0, *w, float(len(regions))]
    for corners in regions:
        pu = np.clip(corners @ u, bu.min(), bu.max())
        pv = np.clip(corners @ v, bv.min(), bv.max())
        du = max(float(np.ptp(pu)), 1e-6 * extent) / max(size[0] - 4, 1)
        dv = max(float(np.ptp(pv)), 1e-6 * extent) / max(size[1] - 4, 1)
        c0 = (pu.min() - 2 * du) * u + (pv.min() - 2 * dv) * v + plane * w
        rows += [*c0, du, 0.0, 0.0, 0.0, dv]
    return rows + [0.0] * (INFO_FLOATS - len(rows))


def map_view(data, size: tuple[int, int]) -> View:
    _cam, basis, tan_half = camera_basis(data)
    return View(basis, tan_half, size[0] / size[1], max(float(data.model.camera.near), 1e-4))


def light_map_info(data, size: tuple[int, int], mapped: int) -> bytes:
    """The std430 table of binding 17 for the first ``mapped`` lights (camera-relative, as the
    lights table of ``pack_tables``): INFO_FLOATS floats each."""
    cam, _basis, _tan = camera_basis(data)
    lo, hi = scene_bounds(data)
    view = map_view(data, size)
    rows: list[float] = []
    for li in data.lights[:mapped]:
        if li.type == 0:
            vec = np.asarray(-li.direction, dtype=np.float32).astype(np.float64)  # as the shader's table
            rows += directional_frame(vec, lo, hi, size, view)
        else:
            rows += [*(np.asarray(li.position, dtype=np.float64) - cam), 1.0] + [0.0] * (INFO_FLOATS - 4)
    return struct.pack(f"<{len(rows)}f", *rows) if rows else bytes(4 * INFO_FLOATS)


def light_map_bindings(setup: Any, data) -> tuple[list[Binding], dict[str, object]]:
    """Bindings 16-17 and the defines of a shading pass that reads ``light_maps`` (nothing
    when no light is mapped: every shadow ray is traced)."""
    mapped = mapped_lights(setup, data)
    if not mapped:
        return [], {}
    info = setup.device_buffer(light_map_info(data, setup.extent_of("light_maps"), mapped))
    guard = float(setup.param("rt.light_map_guard", 2.0))
    if not 0.0 <= guard <= 1e6:
        raise ValueError(f"pass {setup.name!r}: rt.light_map_guard must be in [0, 1e6] pixel footprints, got {guard}")
    return ([Binding(16, "storage_image", "light_maps", array=True), Binding(17, "storage_buffer", buffers=(info,))],
            {"LIGHT_MAPS": 1, "MAPPED_LIGHTS": f"{mapped}u", "LIGHT_MAP_GUARD": repr(guard)})


@register("rt_light_maps")
class LightMaps(RayTracingImpl):
    """Traces the maps of ``light_maps`` (storage_rw: kept between frames) once per set."""

    raygen = "rt/light_map.rgen"
    reads_light_maps = False

    def __init__(self, setup: Any) -> None:
        self.size = setup.extent_of("light_maps")
        super().__init__(setup, [Binding(16, "storage_image", "light_maps", array=True)])
        self.built: set[int] = set()
        self.args = self._indirect_args(setup) if self.mapped else None

    def scene_bindings(self) -> list[Binding]:
        self.mapped = mapped_lights(self.setup, self.data)
        info = self.setup.device_buffer(light_map_info(self.data, self.size, self.mapped))
        return [Binding(17, "storage_buffer", buffers=(info,))]

    def shader_defines(self) -> dict[str, object]:
        return {"MAPPED_LIGHTS": f"{self.mapped}u"}

    @staticmethod
    def _indirect_args(setup: Any) -> Any:
        """Per set the (width, height, depth) of its trace: host-written, device-addressed."""
        from rgraph.vk import names
        from rgraph.vk.loader import vk

        v = vk()
        usage = v.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | names.SHADER_DEVICE_ADDRESS
        return setup.host_buffer(16 * setup.sets, usage, allocate_flags=names.MEMORY_ALLOCATE_DEVICE_ADDRESS)

    def update(self, frame: int, frame_set: int) -> None:
        if self.args is None:
            return
        build = frame_set not in self.built  # the set's first frame: its submit has not run yet
        self.built.add(frame_set)
        dims = (self.size[0], self.size[1], 6 * self.mapped) if build else (0, 1, 1)
        self.args.write(struct.pack("<3I", *dims), 16 * frame_set)

    def record(self, rec: Any, frame_set: int) -> None:
        if self.args is None:
            return
        self._bind(rec, frame_set)
        rec.push(self.pipeline, bytes(64))
        rec.trace_rays_indirect(self.pipeline, rec.buffer_address(self.args.handle) + 16 * frame_set)
