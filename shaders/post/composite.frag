#version 460
// hdr = diffuse + specular (passes/composite_ref.py): finite sums clamp to the half range,
// non-finite inputs pass through for the sanitizing passes downstream.
#extension GL_GOOGLE_include_directive : require
#include "post/common.glsl"

layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 hdr;
#if defined(FULLSCREEN_LAYERS) && FULLSCREEN_LAYERS > 1
// views=2 (passes/composite.py): a layer per eye, this fragment's eye from lib/fullscreen.vert
layout(location = 1) flat in int in_layer;
layout(set = 0, binding = 0) uniform sampler2DArray diffuse;
layout(set = 0, binding = 1) uniform sampler2DArray specular;
#define TEXEL(t, p) texelFetch(t, ivec3(p, in_layer), 0)
#else
layout(set = 0, binding = 0) uniform sampler2D diffuse;
layout(set = 0, binding = 1) uniform sampler2D specular;
#define TEXEL(t, p) texelFetch(t, p, 0)
#endif

float add_clamped(float d, float s) {
    float sum = d + s;
    return (is_finite(d) && is_finite(s)) ? clamp(sum, -HALF_MAX, HALF_MAX) : sum;
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 d = TEXEL(diffuse, p).rgb;
    vec3 s = TEXEL(specular, p).rgb;
    hdr = vec4(add_clamped(d.r, s.r), add_clamped(d.g, s.g), add_clamped(d.b, s.b), 1.0);
}
