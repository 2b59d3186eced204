"""The probe in passes that touch acceleration structures (FORMAT.md 5).

- A compute pass with ``accel_build`` accesses runs the compute probe for its other accesses,
  then builds (or refits) each accel it writes from the probe geometry.
- A raytrace pass runs a ray tracing pipeline whose raygen shader is the compute probe plus
  real rays against each accel it reads (``rgraph.vk.probe_rt_glsl``).
- A compute or raster pass that reads an accel casts the same rays as ray queries
  (``rgraph.vk.probe_glsl``), where the device has them (VK_KHR_ray_query).
"""

from __future__ import annotations

from rgraph.vk.accel import AccelSet
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.passkit import PassSetup, descriptor_types
from rgraph.vk.probe import PROBE, Probe, compile_glsl
from rgraph.vk.probe_rt_glsl import generate_rt
from rgraph.vk.record_context import RecordContext
from rgraph.vk.rt_pipeline import all_rt_stages, create_rt_pipeline


def needs_ray_tracing(plan: dict) -> bool:
    """Whether a plan has accels or raytrace passes (the device then enables ray tracing)."""
    return (any(r["kind"] == "accel" for r in plan["resources"])
            or any(p["kind"] == "raytrace" for p in plan["passes"]))


#: The newest Khronos validation layer known to crash inside vkCreateRayTracingPipelinesKHR
#: (Debian's 1.3.239 on lavapipe: even a raygen-only pipeline; core checks off, it crashes at bind).
CRASHING_LAYER = (1, 3, 239)


def layer_crashes() -> bool:
    """Whether the validation layer in use is one that crashes on ray tracing pipelines."""
    from rgraph.vk.instance import validation_layer_version

    version = validation_layer_version()
    return version is not None and version <= CRASHING_LAYER


def refuse_layer_for_ray_tracing(plan: dict) -> None:
    """Refuse ``--validate`` for plans with raytrace passes when the layer would crash."""
    from rgraph.vk.instance import validation_layer_version

    if not any(p["kind"] == "raytrace" for p in plan["passes"]):
        return
    version = validation_layer_version()
    if version is not None and version <= CRASHING_LAYER:
        raise ExecutionError(
            f"--validate: the installed Khronos validation layer {'.'.join(map(str, version))} crashes inside "
            "vkCreateRayTracingPipelinesKHR; run raytrace passes without --validate (the data check and "
            "`rgraph check` cover them; the layer tracks no ray tracing hazards anyway)")


def probe_class(plan_pass: dict, device) -> type[Probe]:
    """The probe implementation of ``plan_pass`` (a pass without ``impl:``), ray tracing aware.
    A compute or raster pass reading an accel queries rays (FORMAT.md 5: "where the device has
    them"): refused on a device without VK_KHR_ray_query."""
    from rgraph.impl import lookup

    if plan_pass["kind"] == "raytrace":
        return RayTraceProbe
    if "rayQuery" not in device.enabled_features and any(a["usage"] == "accel_read" for a in plan_pass["accesses"]):
        raise ExecutionError(f"pass {plan_pass['name']!r}: a {plan_pass['kind']} pass reads an accel (ray queries), "
                             f"but {device.name} has no ray queries (VK_KHR_ray_query); make it a raytrace pass")
    if any(a["usage"] == "accel_build" for a in plan_pass["accesses"]):
        return AccelBuildProbe
    return lookup(PROBE)  # type: ignore[return-value]


class AccelBuildProbe(Probe):
    """A compute probe pass that then builds (or refits) each accel it writes."""

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        assert setup.accels is not None
        self.accels: AccelSet = setup.accels
        self.builds = [a["resource"] for a in self.p["accesses"] if a["usage"] == "accel_build"]

    def record(self, ctx: RecordContext, set_index: int) -> None:
        super().record(ctx, set_index)
        for name in self.builds:
            ctx.build_accel(self.accels, name, set_index)


class RayTraceProbe(Probe):
    """A raytrace pass: the compute probe as raygen shader plus rays against each accel read."""

    def __init__(self, setup: PassSetup) -> None:
        self.accels: AccelSet | None = setup.accels
        super().__init__(setup)

    def _prepare_shaders(self) -> None:
        self.rt = generate_rt(self.p, self.res_plan, self.plan_size)
        if self.rt.accel_bindings and self.accels is None:
            raise ExecutionError(f"pass {self.p['name']!r}: reads an accel the plan does not build")
        self.shaders = self.rt.base
        self._prepare_rt()

    def _prepare_rt(self) -> None:
        v = vk()
        dev = self.device.handle
        kinds = descriptor_types()
        accel_type = v.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR
        bindings = [(b.binding, kinds[b.kind]) for b in self.shaders.bindings]
        bindings += [(b, accel_type) for b, _ in self.rt.accel_bindings]
        layout_bindings = [v.VkDescriptorSetLayoutBinding(binding=b, descriptorType=t, descriptorCount=1,
                                                          stageFlags=all_rt_stages()) for b, t in bindings]
        self.set_layout = self._own("vkDestroyDescriptorSetLayout", v.vkCreateDescriptorSetLayout(
            dev, v.VkDescriptorSetLayoutCreateInfo(bindingCount=len(layout_bindings),
                                                   pBindings=layout_bindings or None), None))
        if bindings:
            self._allocate_sets([t for _, t in bindings])
            for s in range(self.resources.sets):
                self._write_descriptors(s, kinds)
                self._write_accels(s)
        spirv = {"raygen": [compile_glsl(self.rt.raygen, "rgen")], "miss": [compile_glsl(self.rt.miss, "rmiss")],
                 "closest_hit": [compile_glsl(self.rt.closest_hit, "rchit")]}
        self.pipeline = create_rt_pipeline(self.device, spirv, [self.set_layout])

    def _write_accels(self, set_index: int) -> None:
        v = vk()
        for binding, access in self.rt.accel_bindings:
            name = self.p["accesses"][access]["resource"]
            handles = v.ffi.new("VkAccelerationStructureKHR[1]", [self.accels.tlas(name, set_index)])
            info = v.VkWriteDescriptorSetAccelerationStructureKHR(accelerationStructureCount=1,
                                                                  pAccelerationStructures=handles)
            write = v.VkWriteDescriptorSet(pNext=info, dstSet=self.sets[set_index], dstBinding=binding,
                                           descriptorCount=1,
                                           descriptorType=v.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR)
            v.vkUpdateDescriptorSets(self.device.handle, 1, [write], 0, None)

    def record(self, ctx: RecordContext, set_index: int) -> None:
        ctx.bind(self.pipeline, [self.sets[set_index]] if self.sets else [])
        indirect = [self._resource(i, set_index) for i in self.shaders.indirect_accesses]
        if len(indirect) > 1:
            raise ExecutionError(f"pass {self.p['name']!r}: the probe traces through one indirect buffer")
        if indirect:  # the header's dispatch words (gx, gy, 1): the raygen loop covers the domain
            ctx.trace_rays_indirect(self.pipeline, ctx.buffer_address(indirect[0].handle) + 4 * 12)
        else:
            w, h = self.shaders.domain
            ctx.trace_rays(self.pipeline, w, h)

    def destroy(self) -> None:
        self.pipeline.destroy()
        super().destroy()
