#version 460
// One mip of env_map: the procedural environment prefiltered with GGX for roughness
// mip / (mips - 1), N = V = R (Karis 2013), importance-sampled with Hammersley points.
// NumPy twin: passes/ibl_ref.prefilter.
#extension GL_GOOGLE_include_directive : require
#include "forward/brdf.glsl"
#include "ibl/environment.glsl"
#include "ibl/sampling.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba16f) uniform writeonly image2D dst;
layout(push_constant) uniform Push { float roughness; } pc;

#ifndef SAMPLES
#define SAMPLES 128
#endif

vec3 prefiltered(vec3 n, float roughness) {
    float alpha = ggx_alpha(roughness);
    vec3 t, b;
    onb(n, t, b);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint i = 0u; i < uint(SAMPLES); ++i) {
        vec3 ht = ggx_sample_tangent(hammersley(i, uint(SAMPLES)), alpha);
        vec3 h = ht.x * t + ht.y * b + ht.z * n;
        vec3 l = 2.0 * dot(n, h) * h - n;
        float nol = dot(n, l);
        if (nol > 0.0) {
            sum += env_radiance(l) * nol;
            weight += nol;
        }
    }
    return weight > 0.0 ? sum / weight : env_radiance(n);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    vec3 n = equirect_dir((vec2(p) + 0.5) / vec2(size));
    imageStore(dst, p, vec4(hdr_clamp(prefiltered(n, pc.roughness)), 1.0));
}
