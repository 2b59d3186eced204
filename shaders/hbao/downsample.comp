#version 460
// Working-resolution depth: the NEAREST surface of each k x k block (k = 1 / hbao.scale),
// i.e. the largest reversed-Z value (see passes/hbao_ref.py for why this is the
// conservative choice). At k = 1 a copy.
// views=2 (RGRAPH_VIEWS): a layer per eye, z = the eye; as hbao/common.glsl (not included here,
// so that the views=1 SPIR-V stays exactly what it was).
#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
#define HBAO_SAMPLER sampler2DArray
#define HBAO_IMAGE image2DArray
#define EYE(p) ivec3(p, int(gl_GlobalInvocationID.z))
#define XY(size) (size).xy
#else
#define HBAO_SAMPLER sampler2D
#define HBAO_IMAGE image2D
#define EYE(p) (p)
#define XY(size) (size)
#endif

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform HBAO_SAMPLER depth;
layout(set = 0, binding = 1, r32f) uniform writeonly HBAO_IMAGE depth_quarter;
layout(push_constant) uniform Push {
    int factor;  // k: full-resolution texels per working texel along each axis
} pc;

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, XY(imageSize(depth_quarter))))) return;
    ivec2 size = XY(textureSize(depth, 0));
    ivec2 lo = min(q * pc.factor, size - 1);
    ivec2 hi = min(q * pc.factor + pc.factor, size);
    float nearest = 0.0;
    for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x)
            nearest = max(nearest, texelFetch(depth, EYE(ivec2(x, y)), 0).r);
    imageStore(depth_quarter, EYE(q), vec4(nearest));
}
