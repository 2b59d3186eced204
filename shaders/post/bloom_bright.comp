#version 460
// Bright pass with the Karis average, hdr -> reduced bloom image (passes/bloom_ref.py: bright).
#extension GL_GOOGLE_include_directive : require
#include "post/common.glsl"

// views=2 (RGRAPH_VIEWS, set by passes/bloom.py): src and dst have a layer per eye, bound as
// 2D arrays; the dispatch's z is the eye. views=1: plain 2D images, the same code as before.
#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
#define BLOOM_SAMPLER sampler2DArray
#define BLOOM_IMAGE image2DArray
#define EYE(p) ivec3(p, int(gl_GlobalInvocationID.z))
#define XY(size) (size).xy
#else
#define BLOOM_SAMPLER sampler2D
#define BLOOM_IMAGE image2D
#define EYE(p) (p)
#define XY(size) (size)
#endif

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform BLOOM_SAMPLER src;
layout(set = 0, binding = 1, rgba16f) uniform writeonly BLOOM_IMAGE dst;
layout(push_constant) uniform Push {
    ivec2 factor;     // source texels per output texel along x and y (4 at quarter size)
    float threshold;
    float knee;       // soft-knee width as a fraction of threshold; 0 = hard threshold
    float clamp_max;  // +Inf and larger values are clamped to this before averaging
} pc;

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, XY(imageSize(dst))))) return;
    ivec2 last = XY(textureSize(src, 0)) - 1;
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int j = 0; j < pc.factor.y; ++j) {
        for (int i = 0; i < pc.factor.x; ++i) {
            vec3 c = sanitize(texelFetch(src, EYE(min(q * pc.factor + ivec2(i, j), last)), 0).rgb, pc.clamp_max);
            float w = 1.0 / (1.0 + dot(c, LUMA));
            sum += c * w;
            wsum += w;
        }
    }
    vec3 a = sum / wsum;
    float br = max(a.r, max(a.g, a.b));
    float k = pc.threshold * pc.knee;
    float soft = clamp(br - pc.threshold + k, 0.0, 2.0 * k);
    soft = k > 0.0 ? soft * soft / (4.0 * k + 1e-5) : 0.0;
    float contrib = max(soft, br - pc.threshold) / max(br, 1e-5);
    imageStore(dst, EYE(q), vec4(a * contrib, 1.0));
}
