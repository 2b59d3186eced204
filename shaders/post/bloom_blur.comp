#version 460
// One separable Gaussian pass along pc.dir, clamp to edge (passes/bloom_ref.py: blur).
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
    ivec2 dir;          // (1, 0) horizontal, (0, 1) vertical
    int radius;         // taps -radius..radius
    float weights[29];  // normalized one-sided weights 0..radius
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = XY(imageSize(dst));
    if (any(greaterThanEqual(p, size))) return;
    ivec2 last = XY(textureSize(src, 0)) - 1;
    vec3 c = pc.weights[0] * texelFetch(src, EYE(p), 0).rgb;
    for (int i = 1; i <= pc.radius; ++i) {
        c += pc.weights[i] * (texelFetch(src, EYE(clamp(p + i * pc.dir, ivec2(0), last)), 0).rgb
                              + texelFetch(src, EYE(clamp(p - i * pc.dir, ivec2(0), last)), 0).rgb);
    }
    imageStore(dst, EYE(p), vec4(c, 1.0));
}
