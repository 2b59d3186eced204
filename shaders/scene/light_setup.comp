#version 460
#extension GL_GOOGLE_include_directive : require
// light_setup: authored scene lights (world, float32 hi + lo) -> camera-relative `lights` buffer.
#include "scene/scene.glsl"

layout(local_size_x = 64) in;

layout(set = 1, binding = 0, std430) writeonly buffer LightsOut { Light lights_out[]; };

layout(push_constant) uniform Push {
    ivec4 count;  // x: lights to write
} pc;

void main() {
    // groups fold into rows (rgraph/vk/dispatch.py): more than 65,535 groups of lights
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
    if (i >= uint(pc.count.x)) {
        return;
    }
    SceneLight s = scene_lights[i];
    int type = int(s.position_hi.w);
    Light o;
    vec3 dir = s.direction.xyz;
    float len2 = dot(dir, dir);
    dir = len2 > 1e-30 ? dir * inversesqrt(len2) : vec3(0.0, -1.0, 0.0);
    if (type == LIGHT_DIRECTIONAL) {
        vec3 to_light = -dir;
        o.position = vec4(0.0, 0.0, 0.0, s.position_lo.w);
        o.to_light = vec4(to_light, float(type));
        o.view = vec4(mat3(frame.view) * to_light, 0.0);
    } else {
        // (hi - cam_hi) is exact for nearby values; the low parts restore what float32 lost
        vec3 rel = (s.position_hi.xyz - frame.camera_hi.xyz) + (s.position_lo.xyz - frame.camera_lo.xyz);
        float r = max(s.position_lo.w, 1e-6);
        o.position = vec4(rel, s.position_lo.w);
        o.to_light = vec4(type == LIGHT_SPOT ? -dir : vec3(0.0), float(type));  // spot: minus its axis
        o.view = vec4(mat3(frame.view) * rel, 1.0 / (r * r));
    }
    o.radiance = vec4(s.radiance.rgb, type == LIGHT_SPOT ? -1.0 : s.direction.w);  // spot: w holds its cone
    lights_out[i] = o;
}
