"""The probe's ray tracing shaders for one raytrace pass (pure: no ``vulkan`` import).

The raygen shader is the compute probe of the same accesses (``rgraph.vk.probe_glsl``), one
launch per texel of the pass's domain, plus, per ``accel_read`` access, three rays against
the probe geometry (``rgraph.vk.accel.probe_geometry``): one hitting instance 0, one hitting
instance 1, one missing; the closest-hit shader returns the instance's custom index + 1, the
miss shader ``MISS_VALUE`` (``rgraph.probe.semantics.trace_value``).
"""

from __future__ import annotations

from dataclasses import dataclass

from rgraph.probe.semantics import MISS_VALUE
from rgraph.vk.errors import ExecutionError
from rgraph.vk.probe_glsl import PROBE_RAYS, ProbeShaders, generate, vec3

RT_HEADER = "#version 460\n#extension GL_EXT_ray_tracing : require\n"


@dataclass
class RayTraceProbeShaders:
    base: ProbeShaders  # bindings, domain (as the compute probe)
    accel_bindings: list[tuple[int, int]]  # (binding, access index) per accel_read
    raygen: str
    miss: str
    closest_hit: str


def generate_rt(plan_pass: dict, resources: dict[str, dict], plan_size: tuple[int, int]) -> RayTraceProbeShaders:
    accesses = plan_pass["accesses"]
    base = generate(dict(plan_pass, kind="compute"), resources, plan_size, ray_queries=False)
    src = base.sources["comp"]
    accel_bindings = []
    decls, calls = [], []
    for i, a in enumerate(accesses):
        if a["usage"] != "accel_read":
            continue
        b = len(base.bindings) + len(accel_bindings)
        accel_bindings.append((b, i))
        decls.append(f"layout(set=0, binding={b}) uniform accelerationStructureEXT as{b};")
        for origin, direction in PROBE_RAYS:
            calls.append(f"        traceRayEXT(as{b}, gl_RayFlagsOpaqueEXT, 0xFF, 0, 0, 0, {vec3(origin)}, 0.0, "
                         f"{vec3(direction)}, 100.0, 0); s += probe_payload;")
    for old, new in (("#version 450\n", RT_HEADER), ("layout(local_size_x = 8, local_size_y = 8) in;\n", ""),
                     ("gl_NumWorkGroups.xy * uvec2(8u, 8u)", "gl_LaunchSizeEXT.xy"),
                     ("gl_GlobalInvocationID", "gl_LaunchIDEXT"),
                     ("        uint s = 0u;\n", "        uint s = 0u;\n" + "".join(c + "\n" for c in calls))):
        if old not in src:
            raise ExecutionError(f"pass {plan_pass['name']!r}: unexpected compute probe source")
        src = src.replace(old, new)
    payload = "layout(location = 0) rayPayloadEXT uint probe_payload;\n"
    src = src.replace("void main() {", "\n".join(decls) + "\n" + payload + "void main() {", 1)
    miss = RT_HEADER + "layout(location = 0) rayPayloadInEXT uint probe_payload;\n" \
        f"void main() {{ probe_payload = {MISS_VALUE}u; }}\n"
    hit = RT_HEADER + "layout(location = 0) rayPayloadInEXT uint probe_payload;\n" \
        "void main() { probe_payload = uint(gl_InstanceCustomIndexEXT) + 1u; }\n"
    return RayTraceProbeShaders(base, accel_bindings, src, miss, hit)
