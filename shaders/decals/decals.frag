#version 460
// Box-projected deferred decals, one full-screen pass over every decal of the scene
// (passes/decals_ref.py is the reference). Premultiplied "over" compositing in decal order;
// the pipeline blends src + (1 - src.a) * dst into diffuse and specular.
#extension GL_GOOGLE_include_directive : require
#include "scene/scene.glsl"

layout(location = 0) in vec2 uv;
layout(location = LOC_DIFFUSE) out vec4 out_diffuse;
layout(location = LOC_SPECULAR) out vec4 out_specular;
layout(set = 1, binding = 0) uniform sampler2D depth_tex;   // nearest
layout(set = 1, binding = 1) uniform sampler2D normal_sss;  // nearest; rgb = 0.5 n + 0.5 (world)

const float PI = 3.14159265358979;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float d = texelFetch(depth_tex, p, 0).r;
    out_diffuse = vec4(0.0);
    out_specular = vec4(0.0);
    if (d <= 0.0) return;  // sky: nothing to project onto
    vec2 suv = (vec2(p) + 0.5) * frame.viewport.zw;
    vec3 world = scene_world_from_depth(suv, d);
    vec3 n = texelFetch(normal_sss, p, 0).rgb * 2.0 - 1.0;
    float len = length(n);
    n = len > 1e-3 ? n / len : vec3(0.0);
    vec3 light = frame.ambient.rgb + frame.sun_radiance.rgb * max(dot(n, frame.sun_direction.xyz), 0.0) / PI;
    vec3 color = vec3(0.0);
    float alpha = 0.0;
    for (int k = 0; k < frame.counts.z; ++k) {
        mat4 m = decals[k].world_to_decal;
        vec3 local = (m * vec4(world, 1.0)).xyz;
        if (any(greaterThan(abs(local), vec3(0.5)))) continue;
        vec3 axis = vec3(m[0][2], m[1][2], m[2][2]);  // gradient of local z: the projection axis
        float facing = abs(dot(n, normalize(axis)));
        float a = decals[k].color.a * clamp((facing - 0.25) * 4.0, 0.0, 1.0)
                * clamp((0.5 - abs(local.z)) * 10.0, 0.0, 1.0);
        color = decals[k].color.rgb * light * a + color * (1.0 - a);
        alpha = a + alpha * (1.0 - a);
    }
    out_diffuse = vec4(color, alpha);
    out_specular = vec4(0.0, 0.0, 0.0, alpha);
}
