#version 460
#extension GL_GOOGLE_include_directive : require
// Hybrid, every pixel, without tracing (a compute pass: no ray tracing pipeline, no ray): the
// first surface from the visibility buffer (hybrid.glsl: raster_hit) and its Phong shading where
// nothing needs a ray: the sky, or an opaque surface whose every shadow test the light maps decide
// (light_maps.glsl). Its colour is written here, by the same code the ray tracing pass runs.
// Every other pixel (raster and ray may disagree, the surface reflects or refracts, a shadow test
// the maps cannot tell) is appended to first_list (y << 16 | x) and first_args[0] counts them:
// the shade pass traces only those (trace_rays_indirect). Appends as classify.comp: one global
// atomic per 8x8 tile, row-major within the tile (neighbouring launch slots, neighbouring pixels).
#define NO_TRACE 1
#include "common.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 7, rgba16f) uniform writeonly image2D color_out;
#include "shade.glsl"
#include "hybrid.glsl"
layout(set = 0, binding = 18, r32ui) uniform writeonly uimage2D first_list;
layout(set = 0, binding = 19, std430) buffer FirstArgs { uint first_args[4]; };

shared uint flags[64];
shared uint base;

// Whether pixel px needs a traced ray; if not, its colour in c.
bool needs_rays(uvec2 px, out vec3 c) {
    vec3 d = camera_ray(px);
    c = vec3(0.0);
    Hit h;
    int raster = raster_hit(px, d, h);
    if (raster == 0) { c = sample_sky(d); return false; }
    if (raster < 0) return true;
    vec3 ng, ns; uint m;
    surface(h, d, ng, ns, m);
    vec4 k = mat[2u * m + 1u];
    if (k.x > 0.0 || k.y > 0.0) return true;  // reflects or refracts: its tree is traced
    // shade.glsl: shade_hit of the camera ray (origin 0, weight 1, path 0) on an opaque surface
    bool entering = dot(d, ng) < 0.0;
    undecided = false;
    c = shade_local(h.t * d, entering ? ng : -ng, entering ? ns : -ns, d, m, h.t);
    return undecided;
}

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    uint lid = gl_LocalInvocationIndex;
    bool needs = false;
    if (px.x < frame.counts.x && px.y < frame.counts.y) {
        vec3 c;
        needs = needs_rays(px, c);
        if (!needs) imageStore(color_out, ivec2(px), vec4(c, 1.0));
    }
    flags[lid] = needs ? 1u : 0u;
    barrier();
    uint before = 0u, total = 0u;
    for (uint j = 0u; j < 64u; ++j) { uint f = flags[j]; before += j < lid ? f : 0u; total += f; }
    if (lid == 0u && total > 0u) base = atomicAdd(first_args[0], total);
    barrier();
    if (!needs) return;
    uint slot = base + before;
    imageStore(first_list, ivec2(slot % frame.counts.x, slot / frame.counts.x), uvec4((px.y << 16) | px.x));
}
