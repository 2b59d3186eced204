#version 460
// Split-sum BRDF integration (Karis 2013) with Smith height-correlated visibility:
// texel (x, y) holds (A, B) for N.V = (x + 0.5) / size and perceptual roughness (y + 0.5) / size,
// so that the specular integral is ~ prefiltered * (F0 * A + B). NumPy twin: passes/ibl_ref.brdf_lut.
#extension GL_GOOGLE_include_directive : require
#include "forward/brdf.glsl"
#include "ibl/sampling.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rg16f) uniform writeonly image2D lut;

#ifndef SAMPLES
#define SAMPLES 128
#endif

vec2 integrate(float nov, float roughness) {
    float alpha = ggx_alpha(roughness);
    vec3 v = vec3(sqrt(max(1.0 - nov * nov, 0.0)), 0.0, nov);
    float a = 0.0, b = 0.0;
    for (uint i = 0u; i < uint(SAMPLES); ++i) {
        vec3 h = ggx_sample_tangent(hammersley(i, uint(SAMPLES)), alpha);
        vec3 l = 2.0 * dot(v, h) * h - v;
        float nol = l.z;
        if (nol > 0.0) {
            float noh = max(h.z, 1e-8);
            float voh = clamp(dot(v, h), 0.0, 1.0);
            float g_vis = 4.0 * v_smith_ggx_correlated(nov, min(nol, 1.0), alpha) * nol * voh / noh;
            float x = 1.0 - voh;
            float fc = x * x * x * x * x;
            a += (1.0 - fc) * g_vis;
            b += fc * g_vis;
        }
    }
    return vec2(a, b) / float(SAMPLES);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(lut);
    if (any(greaterThanEqual(p, size))) return;
    vec2 uv = (vec2(p) + 0.5) / vec2(size);
    imageStore(lut, p, vec4(integrate(uv.x, uv.y), 0.0, 0.0));
}
