#version 460
// Box-projected deferred decals, one full-screen pass over every decal of the scene
// (passes/decals_ref.py is the reference). Premultiplied "over" compositing in decal order;
// the pipeline blends src + (1 - src.a) * dst into diffuse and specular.
#extension GL_GOOGLE_include_directive : require
#include "scene/scene.glsl"

layout(location = 0) in vec2 uv;
layout(location = LOC_DIFFUSE) out vec4 out_diffuse;
layout(location = LOC_SPECULAR) out vec4 out_specular;
#if defined(FULLSCREEN_LAYERS) && FULLSCREEN_LAYERS > 1
// views=2 (passes/decals.py): a layer per eye, this fragment's eye from lib/fullscreen.vert
layout(location = 1) flat in int in_layer;
layout(set = 1, binding = 0) uniform sampler2DArray depth_tex;   // nearest
layout(set = 1, binding = 1) uniform sampler2DArray normal_sss;  // nearest; rgb = 0.5 n + 0.5 (world)
#define TEXEL(t, p) texelFetch(t, ivec3(p, in_layer), 0)
#define EYE scene_eye(uint(in_layer))
#else
layout(set = 1, binding = 0) uniform sampler2D depth_tex;   // nearest
layout(set = 1, binding = 1) uniform sampler2D normal_sss;  // nearest; rgb = 0.5 n + 0.5 (world)
#define TEXEL(t, p) texelFetch(t, p, 0)
#endif

const float PI = 3.14159265358979;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float d = TEXEL(depth_tex, p).r;
    out_diffuse = vec4(0.0);
    out_specular = vec4(0.0);
    if (d <= 0.0) return;  // sky: nothing to project onto
    vec2 suv = (vec2(p) + 0.5) * frame.viewport.zw;
#if defined(FULLSCREEN_LAYERS) && FULLSCREEN_LAYERS > 1
    // the eye's inverse view-projection is the centre's followed by a move by the eye's offset
    vec3 world = scene_world_from_depth(suv, d) + EYE;
#else
    vec3 world = scene_world_from_depth(suv, d);
#endif
    vec3 n = TEXEL(normal_sss, p).rgb * 2.0 - 1.0;
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
