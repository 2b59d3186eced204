#version 460
#extension GL_GOOGLE_include_directive : require
// Compute visibility buffer, big triangles: one workgroup per (triangle, tile) job appended by
// the depth pass of rt/visraster.comp (indirect dispatch: args.job_count groups), one thread per
// pixel of the tile. MODE_ID as there; the same setup and coverage code, so the same keys.
#include "rt/visraster.glsl"
layout(local_size_x = TILE, local_size_y = TILE) in;
#ifdef MODE_ID
layout(set = 0, binding = 5, r32ui) uniform readonly uimage2D depth_keys;
layout(set = 0, binding = 6, r32ui) uniform uimage2D visibility;
#else
layout(set = 0, binding = 5, r32ui) uniform uimage2D depth_keys;
#endif
layout(set = 0, binding = 8, std430) readonly buffer Jobs { uvec2 jobs[]; };

void main() {
    uvec2 job = jobs[gl_WorkGroupID.x];
    Tri tri;
    if (!setup_triangle(job.x, tri)) return;
    ivec2 px = ivec2(job.y & 0xFFFFu, job.y >> 16) * TILE + ivec2(gl_LocalInvocationID.xy);
    if (any(lessThan(px, tri.box.xy)) || any(greaterThan(px, tri.box.zw))) return;
    uint key;
    if (!cover(tri, px, key)) return;
#ifdef MODE_ID
    if (imageLoad(depth_keys, px).r == key) imageAtomicMax(visibility, px, tri.id);
#else
    if (imageLoad(depth_keys, px).r < key) imageAtomicMax(depth_keys, px, key);
#endif
}
