"""Hybrid rendering (graphs/rt_hybrid.yaml): a raster visibility buffer, then ray tracing only
where it is needed. Same lighting model and materials as ``rt_standalone``
(``passes.rt_model``); the first surface comes from the visibility buffer instead of a camera ray.

- ``rt_gbuffer`` (raster): ``visibility`` (r32_uint, ((instance << PRIM_BITS) | primitive) + 1;
  0 = nothing) with a d32 reversed-Z depth test; positions only, no attributes;
- ``rt_reset_rays`` (compute): ``ray_args`` = (0, 1, 1), the indirect trace arguments;
- ``rt_classify`` (compute): pixels whose instance's material reflects or refracts are appended
  to ``ray_list`` (packed y << 16 | x), ``ray_args[0]`` counts them;
- ``rt_hybrid_shade`` (raytrace, every pixel): the camera ray intersected with the visible
  triangle (position, barycentrics, normals as the stand-alone's hit), its opaque part (Phong +
  shadow rays) or the sky cube map;
- ``rt_hybrid_secondary`` (raytrace, ``trace_rays_indirect`` over the compacted list): the
  reflection/refraction ray trees of those pixels, added to the colour (storage_rw).
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding

from .raytrace_standalone import RayTracingImpl, frame_constants, max_depth_of
from .rt_model import material_of
from .scene_passes import SCENE_FRONT_FACE

GBUFFER = (Binding(8, "sampled", "visibility", sampler="nearest"),)


def needs_secondary_rays(materials) -> np.ndarray:
    """Per material: 1 when it reflects or refracts (the classification mask)."""
    return np.array([int(material_of(m).kr > 0 or material_of(m).kt > 0) for m in materials] or [0], dtype=np.uint32)


def instance_materials(data) -> np.ndarray:
    """Per TLAS instance (= draw index: mesh-major, then the mesh's positions): its material."""
    return np.array([mesh.material for mesh in data.meshes for _p in mesh.positions] or [0], dtype=np.uint32)


def prim_bits(data) -> int:
    """Bits of the primitive in a visibility-buffer id: enough for the largest mesh; the rest
    must hold every instance (and the + 1 of id 0 = nothing)."""
    bits = max(1, max((m.data.triangle_count - 1 for m in data.meshes), default=0).bit_length())
    instances = len(instance_materials(data))
    if bits >= 32 or (instances << bits) >= 0xFFFFFFFF:
        raise ValueError(f"scene: {instances} instances x 2^{bits} triangles do not fit a 32-bit visibility id")
    return bits


def decode_visibility(ids: np.ndarray, bits: int) -> tuple[np.ndarray, np.ndarray]:
    """(instance, primitive) of visibility-buffer ids (id 0: instance -1)."""
    ids = ids.astype(np.int64)
    return np.where(ids > 0, (ids - 1) >> bits, -1), np.where(ids > 0, (ids - 1) & ((1 << bits) - 1), -1)


@register("rt_gbuffer")
class GBuffer(PassImpl):
    clear_values = {"depth": 0.0, "visibility": (0.0, 0.0, 0.0, 0.0)}
    attachment_load = {"depth": "clear", "visibility": "clear"}

    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        if "geometryShader" not in setup.device.enabled_features:  # gl_PrimitiveID in the fragment shader
            raise ValueError(f"pass {setup.name!r}: the visibility buffer needs the geometryShader feature")
        self.scene = setup.scene
        # no culling: ray tracing sees both faces of every triangle
        self.pipeline = setup.graphics_pipeline(
            "rt/gbuffer.vert", "rt/gbuffer.frag", [self.scene.set_layout], vertex_input=self.scene.position_input,
            defines={"PRIM_BITS": prim_bits(self.scene.data)},
            cull="NONE", front_face=SCENE_FRONT_FACE, depth_test=True, depth_write=True,
            depth_compare="GREATER_OR_EQUAL")

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set)])
        self.scene.draw(rec, frame_set)


@register("rt_reset_rays")
class ResetRays(PassImpl):
    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        self.sets = setup.descriptors([Binding(0, "storage_buffer", "ray_args")])
        self.pipeline = setup.compute_pipeline("rt/reset_rays.comp", [self.sets.layout])

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.dispatch(1, 1)


@register("rt_classify")
class Classify(PassImpl):
    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        from rgraph.scene.build import load_scene_data

        data = load_scene_data(setup.plan["scene_source"], setup.size, int(setup.plan.get("camera", 0)))
        mask = needs_secondary_rays(data.materials)[instance_materials(data)].tobytes()
        flags = setup.host_buffer(len(mask), "storage")
        flags.write(mask)
        self.sets = setup.descriptors([
            Binding(0, "sampled", "visibility", sampler="nearest"), Binding(1, "storage_buffer", "ray_args"),
            Binding(2, "storage_image", "ray_list"), Binding(3, "storage_buffer", buffers=((flags.handle, flags.size),))])
        self.pipeline = setup.compute_pipeline("rt/classify.comp", [self.sets.layout], push_constant_bytes=8,
                                               defines={"PRIM_BITS": prim_bits(data)})
        self.extent = setup.extent_of("visibility")
        self.push = struct.pack("<2I", *self.extent)

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(-(-self.extent[0] // 8), -(-self.extent[1] // 8))


class VisibilityImpl(RayTracingImpl):
    """Ray tracing passes reading the visibility buffer (its id layout is a shader define)."""

    def shader_defines(self) -> dict[str, object]:
        return {"PRIM_BITS": prim_bits(self.data)}


@register("rt_hybrid_shade")
class HybridShade(VisibilityImpl):
    raygen = "rt/hybrid_shade.rgen"

    def __init__(self, setup: Any) -> None:
        super().__init__(setup, [Binding(7, "storage_image", "color"), *GBUFFER])
        self.extent = setup.extent_of("color")
        self.push = frame_constants(self.data, self.extent, max_depth_of(setup))


@register("rt_hybrid_secondary")
class HybridSecondary(VisibilityImpl):
    raygen = "rt/hybrid_secondary.rgen"

    def __init__(self, setup: Any) -> None:
        super().__init__(setup, [Binding(7, "storage_image", "color"), *GBUFFER,
                                 Binding(11, "storage_image", "ray_list")])
        self.push = frame_constants(self.data, setup.extent_of("color"), max_depth_of(setup))

    def record(self, rec: Any, frame_set: int) -> None:
        self.trace_list(rec, frame_set, "ray_args")
