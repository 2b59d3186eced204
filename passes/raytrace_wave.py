"""The hybrid's wavefront ray tree (graphs/rt_hybrid.yaml; docs/raytracing.md explains why):

- ``rt_wave_shade`` (raytrace, every pixel; when it reads ``first_list``, only the pixels listed
  there by ``rt_hybrid_first``, passes/raytrace_first.py): tree level 0. The first surface from the visibility
  buffer, its opaque part (Phong + shadow rays) or the sky; a surface that reflects or refracts
  takes a slot of the pixel list (``ray_list``, ``ray_args`` = (0, 1, 1, count)),
  stores its own radiance in accumulator ``slot`` (``wave_color``: 3 x uint64 fixed point) and
  appends its children to ``rays_1`` (count in ``rays_1_args``);
- ``rt_wave`` (raytrace, ``trace_rays_indirect`` over ``rays_k``): tree level k, one closest-hit
  trace per ray, its radiance added to the owner's accumulator (64-bit integer atomics: the same
  sum in any order), children to ``rays_{k+1}`` when the pass writes it, else walked in-thread;
- ``rt_wave_resolve`` (compute, over the accumulators' capacity; the count read from
  ``ray_args``): the listed pixels' colours.

Nothing is dropped: children that do not fit the next list, pixels past the accumulators'
capacity and everything below the last list are walked in-thread by the stand-alone's stack walk.
Without 64-bit buffer atomics (``shaderBufferInt64Atomics``) or with ``rt.wavefront: 0`` the
shade pass walks every tree in-thread and the other passes record nothing.
"""

from __future__ import annotations

import re
import struct
from typing import Any

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding

from .raytrace_hybrid import GBUFFER, VisibilityImpl
from .raytrace_standalone import frame_constants, max_depth_of

RAY_RECORD = 48  # bytes per ray of rays_k (shaders/rt/wave.glsl: RayRecord)
ACCUM = 24       # bytes per listed pixel of wave_color (3 x uint64)
MAX_WAVE_RESETS = 3  # lists whose arguments rt_vis_clear resets (shaders/rt/visclear.comp)
LIST = re.compile(r"rays_(\d+)$")


def list_name(level: int) -> str:
    return f"rays_{level}"


def list_args(level: int) -> str:
    return f"rays_{level}_args"


def wavefront(setup: Any) -> bool:
    """Whether the tree is traced level by level: the device has 64-bit buffer atomics and
    ``rt.wavefront`` is not 0."""
    return int(setup.param("rt.wavefront", 1)) != 0 and "shaderBufferInt64Atomics" in setup.device.enabled_features


def raygen_subgroups(device: Any) -> bool:
    """Whether ray generation shaders have subgroup ballot + arithmetic operations."""
    from rgraph.vk.loader import vk

    v = vk()
    props = v.VkPhysicalDeviceSubgroupProperties()
    v.vkGetPhysicalDeviceProperties2(device.physical.handle, v.VkPhysicalDeviceProperties2(pNext=props))
    ops = v.VK_SUBGROUP_FEATURE_BALLOT_BIT | v.VK_SUBGROUP_FEATURE_ARITHMETIC_BIT | v.VK_SUBGROUP_FEATURE_BASIC_BIT
    return bool(props.supportedStages & v.VK_SHADER_STAGE_RAYGEN_BIT_KHR) and props.supportedOperations & ops == ops


def append_defines(setup: Any) -> dict[str, object]:
    """``SUBGROUP_APPEND`` with ``rt.wave_subgroup`` 1 where the device can (shaders/rt/wave.glsl)."""
    wanted = int(setup.param("rt.wave_subgroup", 0)) != 0
    return {"SUBGROUP_APPEND": 1} if wanted and raygen_subgroups(setup.device) else {}


def capacity(setup: Any, resource: str, unit: int) -> int:
    return int(setup.resource_plan(resource)["bytes"]) // unit


def wave_bindings(setup: Any, next_level: int) -> tuple[list[Binding], dict[str, object]]:
    """The accumulators and, when the pass writes it, list ``next_level`` (+ its arguments)."""
    bindings = [Binding(12, "storage_buffer", "wave_color")]
    defines: dict[str, object] = {}
    if setup.has(list_name(next_level)):
        bindings += [Binding(13, "storage_buffer", list_name(next_level)),
                     Binding(14, "storage_buffer", list_args(next_level))]
        defines.update(NEXT_LIST=1, RAY_CAPACITY=f"{capacity(setup, list_name(next_level), RAY_RECORD)}u")
    defines.update(append_defines(setup))
    return bindings, defines


class WaveImpl(VisibilityImpl):
    """Ray tracing passes of the wavefront (a pipeline only when the tree is traced by levels)."""

    def __init__(self, setup: Any, images: list[Binding], defines: dict[str, object], enabled: bool) -> None:
        self.defines, self.enabled = defines, enabled
        super().__init__(setup, images)
        self.push = frame_constants(self.data, setup.extent_of("visibility"), max_depth_of(setup))

    def shader_defines(self) -> dict[str, object]:
        return {**super().shader_defines(), **self.defines}

    def _pipeline(self) -> Any:
        return super()._pipeline() if self.enabled else None

    def destroy(self) -> None:
        if self.pipeline is not None:
            self.pipeline.destroy()


@register("rt_wave_shade")
class WaveShade(WaveImpl):
    raygen = "rt/hybrid_wave_shade.rgen"

    def __init__(self, setup: Any) -> None:
        bindings = [Binding(7, "storage_image", "color"), *GBUFFER]
        defines: dict[str, object] = {"SHADE_WALKS": 1}
        if wavefront(setup) and setup.has("wave_color"):
            extent = setup.extent_of("visibility")
            more, defines = wave_bindings(setup, 1)
            pixels = min(extent[0] * extent[1], capacity(setup, "wave_color", ACCUM))
            bindings += [Binding(9, "storage_image", "ray_list"), Binding(10, "storage_buffer", "ray_args"), *more]
            defines.update(WAVEFRONT=1, PIXEL_CAPACITY=f"{pixels}u")
            fits = pixels == extent[0] * extent[1] and "NEXT_LIST" in defines \
                and capacity(setup, list_name(1), RAY_RECORD) >= 2 * pixels
            if fits:  # every pixel has a slot and list 1 room for its children: no in-thread walk
                defines["LIST_FITS"] = 1
            else:
                defines["SHADE_WALKS"] = 1
        self.listed = setup.has("first_list")  # only the pixels rt_hybrid_first could not finish
        if self.listed:
            bindings.append(Binding(18, "storage_image", "first_list"))
            defines["FIRST_LIST"] = 1
        super().__init__(setup, bindings, defines, True)
        self.extent = setup.extent_of("color")

    def record(self, rec: Any, frame_set: int) -> None:
        if self.listed:
            self.trace_list(rec, frame_set, "first_args")
        else:
            super().record(rec, frame_set)


@register("rt_wave")
class Wave(WaveImpl):
    raygen = "rt/hybrid_wave.rgen"

    def __init__(self, setup: Any) -> None:
        levels = [int(m.group(1)) for a in setup.plan_pass["accesses"]
                  if a["usage"] == "storage_read" and (m := LIST.match(a["resource"]))]
        if len(levels) != 1 or not setup.has(list_args(levels[0])):
            raise ValueError(f"pass {setup.name!r}: a wavefront pass reads one list rays_K (storage_read) "
                             f"and its arguments rays_K_args (indirect)")
        self.level = levels[0]
        more, defines = wave_bindings(setup, self.level + 1)
        defines["LEVEL"] = f"{self.level}u"
        super().__init__(setup, [Binding(11, "storage_buffer", list_name(self.level)), *more], defines,
                         wavefront(setup))

    def record(self, rec: Any, frame_set: int) -> None:
        if self.pipeline is None:
            return
        self.trace_list(rec, frame_set, list_args(self.level))


@register("rt_wave_listed")
class WaveListed(WaveImpl):
    """Level 0 of the pixels rt_classify listed (benchmarks/graphs/rt_hybrid_async.yaml): list
    slot = accumulator slot; the other pixels are shaded by rt_hybrid_shade on another queue."""

    raygen = "rt/hybrid_wave_listed.rgen"

    def __init__(self, setup: Any) -> None:
        extent = setup.extent_of("visibility")
        if capacity(setup, "wave_color", ACCUM) < extent[0] * extent[1]:
            raise ValueError(f"pass {setup.name!r}: wave_color must hold a slot per pixel ({ACCUM} bytes each)")
        more, defines = wave_bindings(setup, 1)
        super().__init__(setup, [*GBUFFER, Binding(9, "storage_image", "ray_list"), *more], defines, True)

    def record(self, rec: Any, frame_set: int) -> None:
        self.trace_list(rec, frame_set, "ray_args")


@register("rt_wave_resolve")
class WaveResolve(PassImpl):
    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        self.pipeline = None
        classified = any(p.get("impl") == "rt_classify" for p in setup.plan["passes"])  # count in word 0
        if not (wavefront(setup) or classified):
            return
        self.sets = setup.descriptors([
            Binding(0, "storage_image", "color"), Binding(1, "storage_image", "ray_list"),
            Binding(2, "storage_buffer", "ray_args"), Binding(3, "storage_buffer", "wave_color")])
        extent = setup.extent_of("color")
        pixels = min(extent[0] * extent[1], capacity(setup, "wave_color", ACCUM))
        defines: dict[str, object] = {"PIXEL_CAPACITY": f"{pixels}u"}
        groups = -(-pixels // 64)
        self.groups = (min(groups, 65535), -(-groups // 65535))  # maxComputeWorkGroupCount >= 65535
        if classified:
            defines["COUNT_AT_0"] = 1
        self.pipeline = setup.compute_pipeline("rt/wave_resolve.comp", [self.sets.layout], push_constant_bytes=4,
                                               defines=defines)
        self.push = struct.pack("<I", extent[0])

    def record(self, rec: Any, frame_set: int) -> None:
        if self.pipeline is None:
            return
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups)
