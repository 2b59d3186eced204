// Shared by the HBAO shaders: view-space reconstruction from reversed-Z, infinite-far depth.
// proj = (P00, P11, near, unused): clip = (P00 x, P11 y, near, -z), depth = near / -z, sky = 0.
#ifndef HBAO_COMMON_GLSL
#define HBAO_COMMON_GLSL

// views=2 (passes/hbao.py defines RGRAPH_VIEWS): every image has a layer per eye, bound as a 2D
// array, and the dispatch's z is the eye. The eyes share the projection (they differ by a
// translation only), so nothing else changes. views=1: plain 2D images, the same code as before.
#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
#define HBAO_SAMPLER sampler2DArray
#define HBAO_IMAGE image2DArray
#define EYE(p) ivec3(p, int(gl_GlobalInvocationID.z))  // a texel of this invocation's eye
#define XY(size) (size).xy                              // textureSize / imageSize without the layers
#else
#define HBAO_SAMPLER sampler2D
#define HBAO_IMAGE image2D
#define EYE(p) (p)
#define XY(size) (size)
#endif

vec3 view_position(float depth, vec2 uv, vec4 proj) {
    float z = proj.z / depth;
    vec2 ndc = uv * 2.0 - 1.0;
    return vec3(ndc.x * z / proj.x, ndc.y * z / proj.y, -z);
}

#endif
