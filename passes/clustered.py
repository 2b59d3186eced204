"""Clustered forward lighting (Olsson, Billeter and Assarsson 2012): ``cluster_build``,
``light_assign``, ``forward_clustered`` and ``cluster_heatmap``.

The froxel grid is the graph image ``light_grid`` (rgba32_uint, size ``{scale: 1 / clusters.tile}``,
``layers: clusters.slices``): its extent gives the screen tiles (each ``ceil(output / tiles)``
pixels), its layers the exponential depth slices (``shaders/clustered/clusters.glsl``).

- ``cluster_build`` (compute): each froxel's padded view-space AABB into ``froxel_bounds``
  (rgba32_sfloat, the same extent, 2 layers per slice) and zeroes ``cluster_stats``.
- ``light_assign`` (compute, async-capable): per froxel the lights whose sphere meets its AABB
  (spot lights: and whose cone meets its bounding sphere) as a compact list: ``light_grid``
  = (offset, count) into ``light_indices`` (a uint per entry, ascending light order). A list that
  does not fit ``light_indices`` is marked overflowed (forward shades every light there) and
  counted in ``cluster_stats`` (uint[4]: references asked for, overflowed froxels, longest list,
  capacity): ``rgraph run`` reports it (``cluster_report``). Never a silent drop.
- ``forward_clustered`` (raster): GGX PBR over the froxel's list into ``hdr``; with the param
  ``lighting.mode=all_lights`` the same shader loops over every light (the reference image) and
  ``light_assign`` records nothing.
- ``cluster_heatmap`` (compute): lights shaded per pixel into ``light_heat`` (r32_sfloat).

Params: ``clusters.tile`` (pixels, via the graph's image sizes), ``clusters.slices`` (layers),
``clusters.far`` (m; 0 = the far side of the scene's bounding sphere), ``lighting.mode``
(``clustered`` | ``all_lights``). NumPy reference: ``passes/clustered_ref.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

from rgraph.impl import PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, PassSetup, pack

from .gpu_draw import draw_args
from .scene_passes import SCENE_FRONT_FACE

MODES = ("clustered", "all_lights")
LISTS = ("indices", "bitmask")
LIGHT_BYTES = 64


@dataclass(frozen=True)
class Grid:
    tiles: tuple[int, int]
    slices: int
    tile_px: tuple[int, int]
    far: float

    @property
    def froxels(self) -> int:
        return self.tiles[0] * self.tiles[1] * self.slices


def grid_of(setup: PassSetup) -> Grid:
    """The froxel grid from the plan's ``light_grid`` image and the output size."""
    res = setup.resource_plan("light_grid")
    gx, gy = res["extent"][:2]
    w, h = setup.size
    far = float(setup.param("clusters.far", 0.0))
    if far < 0:
        raise ExecutionError(f"pass {setup.name!r}: clusters.far must be >= 0 (0: from the scene bounds), got {far}")
    return Grid((gx, gy), int(res["layers"]), (-(-w // gx), -(-h // gy)), far)


def lighting_mode(setup: PassSetup) -> str:
    mode = str(setup.param("lighting.mode", "clustered"))
    if mode not in MODES:
        raise ExecutionError(f"pass {setup.name!r}: lighting.mode must be one of {', '.join(MODES)}, got {mode!r}")
    return mode


def list_kind(setup: PassSetup) -> str:
    kind = str(setup.param("clusters.list", "indices"))
    if kind not in LISTS:
        raise ExecutionError(f"pass {setup.name!r}: clusters.list must be one of {', '.join(LISTS)}, got {kind!r}")
    return kind


def cluster_defines(setup: PassSetup) -> dict[str, object]:
    g = grid_of(setup)
    return {"GRID_X": g.tiles[0], "GRID_Y": g.tiles[1], "SLICES": g.slices, "TILE_X": g.tile_px[0],
            "TILE_Y": g.tile_px[1], "CLUSTER_FAR": repr(float(g.far)),
            "ALL_LIGHTS": int(lighting_mode(setup) == "all_lights"), "LIST_BITMASK": int(list_kind(setup) == "bitmask")}


def light_push(setup: PassSetup) -> bytes:
    """(capacity of light_indices in entries, lights to consider) as push constants."""
    count = setup.scene.lights
    if setup.has("lights"):
        count = min(count, setup.buffer("lights", 0)[1] // LIGHT_BYTES)
    capacity = setup.buffer("light_indices", 0)[1] // 4 if setup.has("light_indices") else 0
    return pack("2I", capacity, count)


@register("cluster_build")
class ClusterBuild(PassImpl):
    """See the module docstring."""

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.scene = setup.scene
        self.grid = grid_of(setup)
        self.sets = setup.descriptors([Binding(0, "storage_image", "froxel_bounds", array=True),
                                       Binding(1, "storage_buffer", "cluster_stats")])
        self.pipeline = setup.compute_pipeline("clustered/build.comp", [self.scene.set_layout, self.sets.layout],
                                               defines=cluster_defines(setup))

    def record(self, rec, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        (gx, gy), s = self.grid.tiles, self.grid.slices
        rec.dispatch(-(-gx // 4), -(-gy // 4), -(-s // 4))


@register("light_assign")
class LightAssign(PassImpl):
    """See the module docstring."""

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.scene = setup.scene
        self.grid = grid_of(setup)
        self.active = lighting_mode(setup) == "clustered"
        self.push = light_push(setup)
        self.sets = setup.descriptors([
            Binding(0, "storage_buffer", "lights"), Binding(1, "storage_image", "froxel_bounds", array=True),
            Binding(2, "storage_image", "light_grid", array=True), Binding(3, "storage_buffer", "light_indices"),
            Binding(4, "storage_buffer", "cluster_stats")])
        self.pipeline = setup.compute_pipeline("clustered/assign.comp", [self.scene.set_layout, self.sets.layout],
                                               defines=cluster_defines(setup), push_constant_bytes=8)

    def record(self, rec, frame_set: int) -> None:
        if not self.active:
            return  # all_lights: forward ignores the lists
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(self.grid.tiles[0], self.grid.tiles[1], self.grid.slices)


@register("forward_clustered")
class ForwardClustered(PassImpl):
    """See the module docstring. Depth ``depth_read`` (GREATER_OR_EQUAL against the prepass)."""

    clear_values = {"hdr": (0.0, 0.0, 0.0, 1.0)}
    attachment_load = {"hdr": "clear"}
    multiview = True

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.scene = scene = setup.scene
        self.push = light_push(setup)
        self.sets = setup.descriptors([Binding(0, "storage_buffer", "lights"),
                                       Binding(1, "storage_image", "light_grid", array=True),
                                       Binding(2, "storage_buffer", "light_indices")])
        cull = str(setup.param("depth_prepass.cull", "back")).upper()
        self.pipeline = setup.graphics_pipeline(
            "forward/forward.vert", "clustered/forward.frag", [scene.set_layout, self.sets.layout],
            defines=cluster_defines(setup), push_constant_bytes=8, vertex_input=scene.vertex_input, cull=cull,
            front_face=SCENE_FRONT_FACE, depth_test=True, depth_write=False, depth_compare="GREATER_OR_EQUAL")

    def record(self, rec, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        self.scene.draw(rec, frame_set, args=draw_args(self.setup, frame_set))


@register("cluster_heatmap")
class ClusterHeatmap(PassImpl):
    """See the module docstring."""

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.scene = setup.scene
        self.push = light_push(setup)
        self.w, self.h = setup.extent_of("light_heat")
        left_eye = (0, 1) if int(setup.param("views", 1)) > 1 else None  # views=2: the heatmap of layer 0
        self.sets = setup.descriptors([Binding(0, "sampled", "depth", sampler="nearest", layers=left_eye),
                                       Binding(1, "storage_image", "light_grid", array=True),
                                       Binding(2, "storage_image", "light_heat")])
        self.pipeline = setup.compute_pipeline("clustered/heatmap.comp", [self.scene.set_layout, self.sets.layout],
                                               defines=cluster_defines(setup), push_constant_bytes=8)

    def record(self, rec, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(-(-self.w // 8), -(-self.h // 8))
