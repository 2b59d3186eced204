"""The hybrid's compute shading pass (``impl: rt_hybrid_first``, graphs/rt_hybrid.yaml).

Every pixel, in a compute shader (``shaders/rt/hybrid_first.comp``), without a ray: the first
surface from the visibility buffer and, where nothing needs a ray, its colour (the sky, or an
opaque surface whose every shadow test the light maps decide), by the same shading code as the
ray tracing passes. The other pixels (raster and ray may disagree at the pixel, the surface
reflects or refracts, a shadow test the maps cannot tell) go to ``first_list`` (r32_uint,
``y << 16 | x``) with their count in ``first_args`` (the indirect trace arguments, reset by
``rt_vis_clear``); the shade pass (``rt_wave_shade`` reading ``first_list``) traces only those.

Why: on a GPU without ray tracing cores every pixel of a ray generation launch runs in the ray
tracing pipeline's one big kernel, also the pixels that trace nothing; a compute shader runs them
at the occupancy of its own small kernel (docs/raytracing.md, session 17).
"""

from __future__ import annotations

from typing import Any

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding

from .raytrace_hybrid import GBUFFER, prim_bits
from .raytrace_standalone import RayTracingImpl, frame_constants, max_depth_of, scene_table_bindings

LIST, ARGS = "first_list", "first_args"


@register("rt_hybrid_first")
class HybridFirst(PassImpl):
    param_schema = RayTracingImpl.param_schema

    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        from rgraph.scene.build import load_scene_data

        if not setup.plan.get("scene_source"):
            raise ValueError(f"pass {setup.name!r}: ray tracing needs a scene (--scene)")
        for name in (LIST, ARGS, "color", "visibility"):
            if not setup.has(name):
                raise ValueError(f"pass {setup.name!r}: rt_hybrid_first writes color, {LIST} and {ARGS} "
                                 f"and reads visibility; it does not access {name!r}")
        self.data = load_scene_data(setup.plan["scene_source"], setup.size, int(setup.plan.get("camera", 0)))
        bindings = [*scene_table_bindings(setup, self.data), Binding(7, "storage_image", "color"), *GBUFFER,
                    Binding(18, "storage_image", LIST), Binding(19, "storage_buffer", ARGS)]
        defines: dict[str, object] = {"PRIM_BITS": prim_bits(self.data)}
        if setup.has("light_maps"):
            from .raytrace_lightmap import light_map_bindings

            maps, light_defines = light_map_bindings(setup, self.data)
            bindings += maps
            defines.update(light_defines)
        self.sets = setup.descriptors(bindings)
        self.pipeline = setup.compute_pipeline("rt/hybrid_first.comp", [self.sets.layout], defines=defines,
                                               push_constant_bytes=64)
        self.extent = setup.extent_of("color")
        self.push = frame_constants(self.data, self.extent, max_depth_of(setup))

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(-(-self.extent[0] // 8), -(-self.extent[1] // 8))
