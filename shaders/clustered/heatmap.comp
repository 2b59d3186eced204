#version 460
#extension GL_GOOGLE_include_directive : require
// cluster_heatmap: lights the clustered forward pass shades at each pixel (the length of its
// froxel's list; every light where the list overflowed or with ALL_LIGHTS), 0 on background.
#include "scene/scene.glsl"
#include "clustered/clusters.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 1, binding = 0) uniform sampler2D depth;
layout(set = 1, binding = 1, rgba32ui) uniform readonly uimage2DArray light_grid;
layout(set = 1, binding = 2, r32f) uniform writeonly image2D heat;
layout(push_constant) uniform Push { uint capacity; uint light_count; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(heat)))) return;
    float z = texelFetch(depth, p, 0).r;
    float value = 0.0;
    if (z > 0.0) {
#if ALL_LIGHTS
        value = float(pc.light_count);
#else
        uint count = imageLoad(light_grid, cluster_of(vec2(p) + 0.5, cluster_near() / z)).y;
        value = count == CLUSTER_OVERFLOW ? float(pc.light_count) : float(count);
#endif
    }
    imageStore(heat, p, vec4(value));
}
