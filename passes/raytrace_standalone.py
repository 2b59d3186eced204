"""Stand-alone ray tracing (``impl: rt_standalone``) and its background (``impl: sky_cubemap``).

- ``sky_cubemap`` (compute): ``sky`` (6-layer image, storage_write) <- the procedural sky at
  each texel centre (``passes.rt_model.sky``).
- ``rt_standalone`` (raytrace): reads the scene accel (accel_read) and ``sky`` (sampled),
  writes the pass's storage image: per pixel the ray tree of ``passes.rt_model`` walked
  iteratively (``shaders/rt/shade.glsl``), ``rt.max_depth`` (default 4) deep.
The NumPy reference of both: ``passes/rt_ref.py``.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.passkit import Binding

from .rt_model import MAX_LIGHTS, MAX_STACK, camera_basis, material_of

TABLES = ("instances", "positions", "normals", "indices", "materials", "lights")


def pack_tables(data) -> dict[str, bytes]:
    """The std430 tables of ``shaders/rt/common.glsl`` (instances in TLAS order)."""
    from rgraph.scene.camera import inverse_transpose3, model_matrix

    cam, _basis, _tan = camera_basis(data)
    first_index, first_vertex, inst = [], [], []
    vi = ii = 0
    for mesh in data.meshes:
        first_vertex.append(vi)
        first_index.append(ii)
        vi += mesh.data.vertex_count
        ii += 3 * mesh.data.triangle_count
    for k, mesh in enumerate(data.meshes):
        for p in mesh.positions:
            m = model_matrix(p - cam, mesh.rotation, mesh.scale)
            nm = inverse_transpose3(m)
            rows = np.concatenate([m[:3, :4], np.concatenate([nm, np.zeros((3, 1))], axis=1)]).astype(np.float32)
            inst.append(rows.tobytes() + struct.pack("<4I", first_index[k], mesh.material, first_vertex[k], 0))
    mats = []
    for m in (material_of(x) for x in data.materials):
        mats.append(struct.pack("<8f", *m.albedo, m.ks, m.kr, m.kt, m.ior, m.shininess))
    lights = []
    for li in data.lights[:MAX_LIGHTS]:
        vec = -li.direction if li.type == 0 else li.position - cam
        lights.append(struct.pack("<8f", *vec, float(li.type != 0), *li.radiance, 0.0))
    return {
        "instances": b"".join(inst),
        "positions": np.concatenate([m.data.positions for m in data.meshes]).astype(np.float32).tobytes(),
        "normals": np.concatenate([m.data.normals for m in data.meshes]).astype(np.float32).tobytes(),
        "indices": np.concatenate([m.data.indices.ravel() for m in data.meshes]).astype(np.uint32).tobytes(),
        "materials": b"".join(mats) or bytes(32),
        "lights": b"".join(lights) or bytes(32),
    }


def deformed_tables(setup) -> Any:
    """The deformed geometry the plan's accels are built from (``rgraph.vk.rt_deform``): per set
    positions and normals the scene-table readers bind instead of the static ones; None when
    the scene has no deformable meshes or no accel is built every frame."""
    return getattr(setup.accels, "deformed", None)


def scene_table_bindings(setup: Any, data) -> list[Binding]:
    """Set 0 bindings 0-5 (the scene tables; over deformable meshes positions and normals are the
    frame's, per set) and 6 (the sky) of the passes that shade with ``shaders/rt/common.glsl``."""
    tables = pack_tables(data)
    deformed = deformed_tables(setup)
    bindings = []
    for i, name in enumerate(TABLES):  # device-local: every hit reads them, every frame
        if deformed is not None and name in ("positions", "normals"):  # per set, the frame's
            buffers = deformed.position_buffers() if name == "positions" else deformed.normal_buffers()
            bindings.append(Binding(i, "storage_buffer", buffers=buffers))
            continue
        bindings.append(Binding(i, "storage_buffer", buffers=(setup.device_buffer(tables[name]),)))
    bindings.append(Binding(6, "sampled", "sky", array=True, sampler="nearest"))
    return bindings


def frame_constants(data, size: tuple[int, int], max_depth: int) -> bytes:
    _cam, basis, tan_half = camera_basis(data)
    right, up, fwd = basis
    near = float(data.model.camera.near)
    return struct.pack("<12f4I", *right, tan_half, *up, size[0] / size[1], *fwd, near, size[0], size[1], max_depth,
                       min(len(data.lights), MAX_LIGHTS))


def max_depth_of(setup) -> int:
    depth = int(setup.param("rt.max_depth", 4))
    if not 1 <= depth < MAX_STACK:
        raise ValueError(f"pass {setup.name!r}: rt.max_depth must be 1 .. {MAX_STACK - 1}, got {depth}")
    return depth


@register("sky_cubemap")
class SkyCubemap(PassImpl):
    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        self.sets = setup.descriptors([Binding(0, "storage_image", "sky", array=True)])
        self.pipeline = setup.compute_pipeline("rt/sky.comp", [self.sets.layout])
        size = setup.extent_of("sky")
        self.groups = (-(-size[0] // 8), -(-size[1] // 8), 6)

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.dispatch(*self.groups)


class RayTracingImpl(PassImpl):
    """Common setup of the ray tracing implementations: scene tables (set 0, bindings 0-5;
    over deformable meshes positions and normals are the frame's, per set: ``deformed_tables``),
    the sky (binding 6), the pass's own images from binding 7, the TLAS (set 1)."""

    raygen = "rt/standalone.rgen"
    param_schema = {"rt.max_depth": Param(int, 1, MAX_STACK - 1), "rt.light_maps": Param(int, choices=(0, 1)),
                    "rt.light_map_guard": Param(float, 0, 1e6)}
    #: A pass that reads ``light_maps`` tests its shadow rays against them first
    #: (``passes.raytrace_lightmap``); the pass that traces the maps binds them itself.
    reads_light_maps = True

    def __init__(self, setup: Any, images: list[Binding]) -> None:
        super().__init__(setup)
        from rgraph.scene.build import load_scene_data

        if not setup.plan.get("scene_source"):
            raise ValueError(f"pass {setup.name!r}: ray tracing needs a scene (--scene)")
        self.data = load_scene_data(setup.plan["scene_source"], setup.size, int(setup.plan.get("camera", 0)))
        bindings = scene_table_bindings(setup, self.data)
        images = [*images, *self.scene_bindings()]
        self.light_defines: dict[str, object] = {}
        if self.reads_light_maps and setup.has("light_maps"):
            from .raytrace_lightmap import light_map_bindings

            maps, self.light_defines = light_map_bindings(setup, self.data)
            images = [*images, *maps]
        self.sets = setup.descriptors(bindings + images)
        self.accel = next(a["resource"] for a in setup.plan_pass["accesses"] if a["usage"] == "accel_read")
        self.as_layout, self.as_sets = self._tlas_sets()
        self.written: set[int] = set()
        self.pipeline = self._pipeline()

    def _tlas_sets(self) -> tuple[Any, list[Any]]:
        from rgraph.vk.loader import vk
        from rgraph.vk.rt_pipeline import all_rt_stages

        v = vk()
        setup, dev = self.setup, self.setup.device.handle
        binding = [v.VkDescriptorSetLayoutBinding(binding=0, descriptorType=v.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR,
                                                  descriptorCount=1, stageFlags=all_rt_stages())]
        layout = setup.own("vkDestroyDescriptorSetLayout", v.vkCreateDescriptorSetLayout(
            dev, v.VkDescriptorSetLayoutCreateInfo(bindingCount=1, pBindings=binding), None))
        sizes = [v.VkDescriptorPoolSize(type=v.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, descriptorCount=setup.sets)]
        pool = setup.own("vkDestroyDescriptorPool", v.vkCreateDescriptorPool(dev, v.VkDescriptorPoolCreateInfo(
            maxSets=setup.sets, poolSizeCount=1, pPoolSizes=sizes), None))
        sets = v.vkAllocateDescriptorSets(dev, v.VkDescriptorSetAllocateInfo(
            descriptorPool=pool, descriptorSetCount=setup.sets, pSetLayouts=[layout] * setup.sets))
        return layout, list(sets)

    def shader_defines(self) -> dict[str, object]:
        """Defines of the pipeline's shaders (``self.data`` is loaded)."""
        return {}

    def scene_bindings(self) -> list[Binding]:
        """More bindings of the pass that depend on the scene (``self.data`` is loaded)."""
        return []

    def _pipeline(self) -> Any:
        from rgraph.vk.rt_pipeline import create_rt_pipeline
        from rgraph.vk.shaders import compile_shader, find_shader

        def spirv(path: str) -> bytes:
            return compile_shader(find_shader(path), defines={**self.shader_defines(), **self.light_defines}).spirv

        return create_rt_pipeline(self.setup.device, {
            "raygen": [spirv(self.raygen)], "miss": [spirv("rt/miss.rmiss"), spirv("rt/shadow.rmiss")],
            "closest_hit": [spirv("rt/hit.rchit")]}, [self.sets.layout, self.as_layout], push_bytes=64)

    def _bind(self, rec: Any, frame_set: int) -> None:
        from rgraph.vk.loader import vk

        if frame_set not in self.written:  # the TLAS exists once the executor's AccelSet does
            v = vk()
            handles = v.ffi.new("VkAccelerationStructureKHR[1]", [self.setup.accels.tlas(self.accel, frame_set)])
            info = v.VkWriteDescriptorSetAccelerationStructureKHR(accelerationStructureCount=1,
                                                                  pAccelerationStructures=handles)
            write = v.VkWriteDescriptorSet(pNext=info, dstSet=self.as_sets[frame_set], dstBinding=0, descriptorCount=1,
                                           descriptorType=v.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR)
            v.vkUpdateDescriptorSets(self.setup.device.handle, 1, [write], 0, None)
            self.written.add(frame_set)
        rec.bind(self.pipeline, [self.sets[frame_set], self.as_sets[frame_set]])

    def record(self, rec: Any, frame_set: int) -> None:
        """One ray per texel of ``self.extent`` with ``self.push`` (passes that trace over a
        list override this)."""
        self._bind(rec, frame_set)
        rec.push(self.pipeline, self.push)
        rec.trace_rays(self.pipeline, *self.extent)

    def trace_list(self, rec: Any, frame_set: int, args: str) -> None:
        """One ray per entry of a compacted list: the indirect trace arguments in buffer ``args``."""
        self._bind(rec, frame_set)
        rec.push(self.pipeline, self.push)
        buffer, _size = self.setup.buffer(args, frame_set)
        rec.trace_rays_indirect(self.pipeline, rec.buffer_address(buffer))

    def destroy(self) -> None:
        self.pipeline.destroy()


@register("rt_standalone")
class RTStandalone(RayTracingImpl):
    def __init__(self, setup: Any) -> None:
        self.output = next(a["resource"] for a in setup.plan_pass["accesses"] if a["usage"] == "storage_write")
        super().__init__(setup, [Binding(7, "storage_image", self.output)])
        self.extent = setup.extent_of(self.output)
        self.push = frame_constants(self.data, self.extent, max_depth_of(setup))
