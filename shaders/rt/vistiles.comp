#version 460
#extension GL_GOOGLE_include_directive : require
// Compute visibility buffer, big triangles: one 16x16 workgroup per (triangle, tile) job appended
// by the depth pass of rt/visraster.comp (indirect dispatch: args.job_count groups); the first
// thread sets the triangle up once for the group, each thread then does 2x2 pixels of the
// TILE x TILE tile. MODE_ID as there; the same setup and coverage code, so the same keys.
#include "rt/visraster.glsl"
layout(local_size_x = 16, local_size_y = 16) in;
#ifdef MODE_ID
layout(set = 0, binding = 5, r32ui) uniform readonly uimage2D depth_keys;
layout(set = 0, binding = 6, r32ui) uniform uimage2D visibility;
#else
layout(set = 0, binding = 5, r32ui) uniform uimage2D depth_keys;
#endif
layout(set = 0, binding = 8, std430) readonly buffer Jobs { uvec2 jobs[]; };

shared Tri group_tri;
shared bool group_ok;

void main() {
    uvec2 job = jobs[gl_WorkGroupID.x];
    if (gl_LocalInvocationIndex == 0u) {
        Tri t;
        group_ok = setup_triangle(job.x, t);
        group_tri = t;
    }
    barrier();
    if (!group_ok) return;
    Tri tri = group_tri;
    ivec2 origin = ivec2(job.y & 0xFFFFu, job.y >> 16) * TILE + ivec2(gl_LocalInvocationID.xy);
    for (int k = 0; k < (TILE / 16) * (TILE / 16); ++k) {
        ivec2 px = origin + 16 * ivec2(k % (TILE / 16), k / (TILE / 16));
        if (any(lessThan(px, tri.box.xy)) || any(greaterThan(px, tri.box.zw))) continue;
        uint key;
        if (!cover(tri, px, key)) continue;
#ifdef MODE_ID
        if (imageLoad(depth_keys, px).r == key) imageAtomicMax(visibility, px, tri.id);
#else
        if (imageLoad(depth_keys, px).r < key) imageAtomicMax(depth_keys, px, key);
#endif
    }
}
