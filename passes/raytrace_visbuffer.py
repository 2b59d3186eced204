"""The hybrid's visibility buffer rasterized in compute shaders (graphs/rt_hybrid.yaml), the
same r32_uint ids as the hardware raster ``rt_gbuffer`` (graphs/rt_hybrid_raster.yaml), formed
by the camera rays' own test (shaders/rt/visraster.glsl explains the method):

- ``rt_vis_clear``: ``vis_depth`` and ``visibility`` 0, ``vis_args`` = (0, 1, 1), the job list's
  count and overflow flag (``vis_jobs`` header) 0, and ``ray_args`` = (0, 1, 1) when the pass
  writes it (one pass fewer than ``rt_reset_rays``), likewise the wavefront lists' arguments
  ``rays_1_args`` .. ``rays_3_args`` it writes (passes/raytrace_wave.py);
- ``rt_vis_depth``: a thread per triangle, atomicMax of the depth key; triangles whose screen box
  exceeds ``rt.vis_big_pixels`` append a job per 32x32 tile of their box to ``vis_jobs``
  (capacity (bytes - 16) / 8, at most 8 x 65535) after storing its setup in ``vis_tris`` (80
  bytes each), and raise ``vis_args``' group count; on overflow the thread rasterizes its box
  itself;
- ``rt_vis_depth_tiles``: 8 jobs per 16x16 workgroup (indirect dispatch over ``vis_args``);
- ``rt_vis_id`` / ``rt_vis_id_tiles``: the same, writing the id where the key is the stored one.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding

from .raytrace_hybrid import prim_bits
from .raytrace_standalone import deformed_tables, pack_tables
from .raytrace_wave import MAX_WAVE_RESETS, list_args
from .rt_model import camera_basis

TILE = 32  # pixels per side of a tile job (shaders/rt/visraster.glsl)
JOBS_PER_GROUP = 8
MAX_JOBS = 65535 * JOBS_PER_GROUP  # maxComputeWorkGroupCount[0] is at least 65535 on every device
JOB_HEADER = 16  # vis_jobs: job count, overflow flag, record count, padding, then (record, tile) pairs
RECORD_BYTES = 80  # vis_tris: a big triangle's setup (shaders/rt/visraster.glsl: TriRecord)
GROUP = 64        # threads per workgroup of the per-triangle passes
CLIP_FRACTION = 1e-3  # the bounding boxes' clip plane: this share of the camera's near distance


def triangle_starts(data) -> np.ndarray:
    """Per TLAS instance (mesh-major): the global index of its first triangle."""
    counts = [mesh.data.triangle_count for mesh in data.meshes for _p in mesh.positions]
    return np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.uint32) if counts else np.zeros(1, np.uint32)


def raster_constants(data, size: tuple[int, int]) -> bytes:
    """The push block of shaders/rt/visraster.glsl (the camera of shade.glsl: camera_ray)."""
    _cam, (right, up, fwd), tan_half = camera_basis(data)
    triangles = sum(mesh.data.triangle_count * len(mesh.positions) for mesh in data.meshes)
    instances = sum(len(mesh.positions) for mesh in data.meshes)
    clip = CLIP_FRACTION * float(data.model.camera.near)
    return struct.pack("<12f4I", *right, tan_half, *up, size[0] / size[1], *fwd, clip, size[0], size[1],
                       triangles, max(instances, 1))


def groups_for(items: int, per_group: int = GROUP) -> tuple[int, int]:
    """A 2D dispatch covering ``items`` (x at most 32768 groups; the shader linearizes)."""
    groups = max(1, -(-items // per_group))
    x = min(groups, 32768)
    return x, -(-groups // x)


def atomic64(setup: Any) -> bool:
    """Whether the visibility buffer takes the one-pass 64-bit path: the device has 64-bit buffer
    atomics, ``rt.vis_atomic64`` is not 0 and the graph's ``vis_keys`` holds a uint64 per pixel
    (else the two-pass 32-bit path). Every pass of the visibility buffer decides alike."""
    if int(setup.param("rt.vis_atomic64", 1)) == 0 or "shaderBufferInt64Atomics" not in setup.device.enabled_features:
        return False
    try:
        keys = int(setup.resource_plan("vis_keys")["bytes"])
    except KeyError:
        return False
    w, h = setup.extent_of("visibility")
    return keys >= 8 * w * h


class VisPass(PassImpl):
    """Common setup: geometry tables (device-local; over deformable meshes the positions are
    the frame's, per set: ``deformed_tables``), the per-instance triangle starts, the
    visibility-buffer images and the job list, the push constants."""

    shader = "rt/visraster.comp"
    mode_id = False
    uses_args = True     # binding 7 in the shader
    uses_records = True  # binding 10: the big triangles' setup records

    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        from rgraph.scene.build import load_scene_data

        if not setup.plan.get("scene_source"):
            raise ValueError(f"pass {setup.name!r}: the visibility buffer needs a scene (--scene)")
        self.data = load_scene_data(setup.plan["scene_source"], setup.size, int(setup.plan.get("camera", 0)))
        tables = pack_tables(self.data)
        deformed = deformed_tables(setup)
        bindings = [Binding(i, "storage_buffer", buffers=(setup.device_buffer(tables[name]),)
                            if deformed is None or name != "positions" else deformed.position_buffers())
                    for i, name in ((0, "instances"), (1, "positions"), (3, "indices"))]
        bindings.append(Binding(4, "storage_buffer", buffers=(setup.device_buffer(triangle_starts(self.data).tobytes()),)))
        bindings.append(Binding(5, "storage_image", "vis_depth"))
        if self.mode_id:
            bindings.append(Binding(6, "storage_image", "visibility"))
        if self.uses_args:
            bindings.append(Binding(7, "storage_buffer", "vis_args"))
        bindings.append(Binding(8, "storage_buffer", "vis_jobs"))
        if self.uses_records:
            bindings.append(Binding(10, "storage_buffer", "vis_tris"))
        wide = atomic64(setup) and not self.mode_id
        if wide:
            bindings.append(Binding(15, "storage_buffer", "vis_keys"))
        self.sets = setup.descriptors(bindings)
        records = int(setup.resource_plan("vis_tris")["bytes"]) // RECORD_BYTES if self.uses_records else 1
        capacity = min(MAX_JOBS, (int(setup.resource_plan("vis_jobs")["bytes"]) - JOB_HEADER) // 8)
        big = int(setup.param("rt.vis_big_pixels", 256))
        if capacity < 1 or records < 1 or big < 1:
            raise ValueError(f"pass {setup.name!r}: vis_jobs must hold a job (16 + 8 bytes), vis_tris a record "
                             f"({RECORD_BYTES} bytes) and rt.vis_big_pixels be >= 1")
        defines: dict[str, object] = {"PRIM_BITS": prim_bits(self.data), "BIG_PIXELS": f"{big}u",
                                      "JOB_CAPACITY": f"{capacity}u", "TILE": TILE,
                                      "JOBS_PER_GROUP": f"{JOBS_PER_GROUP}u", "TRI_CAPACITY": f"{records}u"}
        if self.mode_id:
            defines["MODE_ID"] = 1
        if wide:
            defines["ATOMIC64"] = 1
        self.pipeline = setup.compute_pipeline(self.shader, [self.sets.layout], defines=defines, push_constant_bytes=64)
        self.push = raster_constants(self.data, setup.extent_of("visibility"))
        self.groups = groups_for(struct.unpack_from("<I", self.push, 56)[0])

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups)


class VisTiles(VisPass):
    """The big triangles' tile jobs: 8 per workgroup, dispatched indirectly from vis_args."""

    shader = "rt/vistiles.comp"
    uses_args = False

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        args, _size = self.setup.buffer("vis_args", frame_set)
        rec.dispatch_indirect(args, 0)


@register("rt_vis_depth")
class VisDepth(VisPass):
    pass


class VisResolve64(PassImpl):
    """The 64-bit path's id pass: the ids unpacked from ``vis_keys`` (rt/visresolve.comp)."""

    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        self.sets = setup.descriptors([Binding(6, "storage_image", "visibility"),
                                       Binding(15, "storage_buffer", "vis_keys")])
        self.pipeline = setup.compute_pipeline("rt/visresolve.comp", [self.sets.layout])
        w, h = setup.extent_of("visibility")
        self.groups = (-(-w // 8), -(-h // 8))

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.dispatch(*self.groups)


class Idle(PassImpl):
    """The 64-bit path's id tile pass: nothing left to do (the depth passes wrote the ids)."""

    def record(self, rec: Any, frame_set: int) -> None:
        return


class VisId(VisPass):
    mode_id = True
    uses_args = False
    uses_records = False


class VisIdTiles(VisTiles):
    mode_id = True


@register("rt_vis_depth_tiles")
class VisDepthTiles(VisTiles):
    pass


@register("rt_vis_id")
class VisIdPass(PassImpl):
    """The id pass: unpacking on the 64-bit path, else the second rasterization."""

    def __new__(cls, setup: Any) -> PassImpl:  # type: ignore[misc]
        return VisResolve64(setup) if atomic64(setup) else VisId(setup)


@register("rt_vis_id_tiles")
class VisIdTilesPass(PassImpl):
    """The id tile pass: nothing on the 64-bit path, else the big triangles' second rasterization."""

    def __new__(cls, setup: Any) -> PassImpl:  # type: ignore[misc]
        return Idle(setup) if atomic64(setup) else VisIdTiles(setup)


@register("rt_vis_clear")
class VisClear(PassImpl):
    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        bindings = [Binding(5, "storage_image", "vis_depth"), Binding(6, "storage_image", "visibility"),
                    Binding(7, "storage_buffer", "vis_args"), Binding(8, "storage_buffer", "vis_jobs")]
        defines: dict[str, object] = {}
        if setup.has("ray_args"):  # also reset the compacted ray list (instead of rt_reset_rays)
            bindings.append(Binding(9, "storage_buffer", "ray_args"))
            defines["RESET_RAYS"] = 1
        if setup.has("first_args"):  # and the compute shading pass's list (passes/raytrace_first.py)
            bindings.append(Binding(13, "storage_buffer", "first_args"))
            defines["RESET_FIRST"] = 1
        levels = 0  # and the wavefront lists' arguments (passes/raytrace_wave.py)
        while levels < MAX_WAVE_RESETS and setup.has(list_args(levels + 1)):
            bindings.append(Binding(10 + levels, "storage_buffer", list_args(levels + 1)))
            levels += 1
        if levels:
            defines["WAVE_LEVELS"] = levels
        if atomic64(setup) and setup.has("vis_keys"):
            bindings.append(Binding(15, "storage_buffer", "vis_keys"))
            defines["CLEAR_KEYS"] = 1
        self.sets = setup.descriptors(bindings)
        self.pipeline = setup.compute_pipeline("rt/visclear.comp", [self.sets.layout], defines=defines or None)
        w, h = setup.extent_of("visibility")
        self.groups = (-(-w // 8), -(-h // 8))

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.dispatch(*self.groups)
