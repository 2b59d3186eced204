#version 460
#extension GL_GOOGLE_include_directive : require
// Compute visibility buffer, big triangles: the (triangle, tile) jobs appended by the depth pass
// of rt/visraster.comp, JOBS_PER_GROUP per 16x16 workgroup (indirect dispatch: the group count
// that pass set); per job the group reads the triangle's setup record that pass stored, drops the
// job when the tile lies outside one of the triangle's edges (corner test), then each
// thread does (TILE / 16)^2 pixels of the TILE x TILE tile (tiles counted from the triangle's box
// corner). MODE_ID and ATOMIC64 as there; both passes read the same record, so the same keys.
#include "rt/visraster.glsl"
layout(local_size_x = 16, local_size_y = 16) in;
#ifdef MODE_ID
layout(set = 0, binding = 5, r32ui) uniform readonly uimage2D depth_keys;
layout(set = 0, binding = 6, r32ui) uniform uimage2D visibility;
#else
layout(set = 0, binding = 5, r32ui) uniform uimage2D depth_keys;
#endif
layout(set = 0, binding = 8, std430) readonly buffer Jobs { uint job_count; uint overflow; uint tri_count; uint pad; uvec2 jobs[]; };
layout(set = 0, binding = 10, std430) readonly buffer Records { TriRecord records[]; };

void main() {
    uint first = gl_WorkGroupID.x * JOBS_PER_GROUP, last = min(first + JOBS_PER_GROUP, job_count);
    for (uint j = first; j < last; ++j) {  // uniform over the group
        uvec2 job = jobs[j];
        Tri tri = unpack_tri(records[job.x]);  // the depth pass's setup (one broadcast load)
        ivec2 tile = tri.box.xy + ivec2(job.y & 0xFFFFu, job.y >> 16) * TILE;
        if (!tile_may_cover(tri, ivec2(job.y & 0xFFFFu, job.y >> 16))) continue;  // outside an edge
        ivec2 origin = tile + ivec2(gl_LocalInvocationID.xy);
        for (int k = 0; k < (TILE / 16) * (TILE / 16); ++k) {
            ivec2 px = origin + 16 * ivec2(k % (TILE / 16), k / (TILE / 16));
            if (any(greaterThan(px, tri.box.zw))) continue;
            uint key;
            if (!cover(tri, px, key)) continue;
#ifdef MODE_ID
            if (key_matches(key, imageLoad(depth_keys, px).r)) imageAtomicMax(visibility, px, tri.id);
#elif defined(ATOMIC64)
            visit64(px, key, tri.id);
#else
            if (imageLoad(depth_keys, px).r < key) imageAtomicMax(depth_keys, px, key);
#endif
        }
    }
}
