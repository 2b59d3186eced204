#version 460
#extension GL_GOOGLE_include_directive : require
// cluster_build: each froxel's padded view-space AABB (froxel_bounds layer 2k = min, 2k + 1 = max
// of slice k), and zeroes the assignment statistics.
#include "scene/scene.glsl"
#include "clustered/clusters.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(set = 1, binding = 0, rgba32f) uniform writeonly image2DArray froxel_bounds;
layout(set = 1, binding = 1, std430) writeonly buffer Stats { uint stats[4]; };

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (c == ivec3(0)) {
        stats[0] = 0u; stats[1] = 0u; stats[2] = 0u; stats[3] = 0u;
    }
    if (any(greaterThanEqual(c, ivec3(GRID_X, GRID_Y, SLICES)))) return;
    vec3 lo, hi;
    cluster_bounds(c, lo, hi);
    vec3 pad = vec3(cluster_pad(c.z));
#if RGRAPH_VIEWS > 1
    // stereo: one grid for both eyes (same rotation and projection, eyes apart along view x):
    // grow each froxel by the eyes' view-space offsets so its list serves the same tile of either eye
    vec3 eyes = vec3(0.0);
    for (int v = 0; v < RGRAPH_VIEWS; ++v) eyes = max(eyes, abs(mat3(frame.view) * views.eye[v].xyz));
    pad += eyes;
#endif
    imageStore(froxel_bounds, ivec3(c.xy, 2 * c.z), vec4(lo - pad, 0.0));
    imageStore(froxel_bounds, ivec3(c.xy, 2 * c.z + 1), vec4(hi + pad, 0.0));
}
