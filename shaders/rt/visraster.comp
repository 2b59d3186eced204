#version 460
#extension GL_GOOGLE_include_directive : require
// Compute visibility buffer, one thread per triangle (rt/visraster.glsl). MODE_ID undefined: the
// depth pass (atomicMax of the key). A triangle whose box exceeds BIG_PIXELS reserves (one atomic)
// a record of its setup and a job per TILE x TILE tile of its box (tiles from the box's corner, so
// a medium triangle is one job) for rt/vistiles.comp, where a workgroup does JOBS_PER_GROUP jobs: walls and floors do not
// serialize on one thread; the indirect group count becomes ceil(jobs / JOBS_PER_GROUP)
// (atomicMax). When the list is full (JOB_CAPACITY) the reservation is undone (a reservation made
// while an undone one is pending fails too, so the list stays contiguous and ends within the
// capacity; likewise a record past TRI_CAPACITY), the overflow flag is set and the thread
// rasterizes its box itself. MODE_ID: the id
// pass (atomicMax of the id where the key equals the stored one); big triangles are left to the
// tile jobs unless the depth pass overflowed: then every big triangle is also done here (the
// jobs that did run write the same ids again: atomicMax is idempotent).
// ATOMIC64 (the depth pass only): one 64-bit atomicMax of (key << 32 | id) per covered pixel into
// vis_keys (rt/visraster.glsl: visit64), so depth and id come from one pass; rt/visresolve.comp
// then unpacks the ids.
#include "rt/visraster.glsl"
layout(local_size_x = 64) in;
#ifndef CULL_TILES
#define CULL_TILES 64u
#endif
#ifdef MODE_ID
layout(set = 0, binding = 5, r32ui) uniform readonly uimage2D depth_keys;
layout(set = 0, binding = 6, r32ui) uniform uimage2D visibility;
layout(set = 0, binding = 8, std430) readonly buffer Jobs { uint job_count; uint overflow; uint tri_count; uint pad; uvec2 jobs[]; };
#else
layout(set = 0, binding = 5, r32ui) uniform uimage2D depth_keys;
layout(set = 0, binding = 7, std430) buffer Args { uint groups; uint y; uint z; uint w; } args;
layout(set = 0, binding = 8, std430) buffer Jobs { uint job_count; uint overflow; uint tri_count; uint pad; uvec2 jobs[]; };
layout(set = 0, binding = 10, std430) writeonly buffer Records { TriRecord records[]; };
#endif

void visit(Tri tri, ivec2 px) {
    uint key;
    if (!cover(tri, px, key)) return;
#ifdef MODE_ID
    if (key_matches(key, imageLoad(depth_keys, px).r)) imageAtomicMax(visibility, px, tri.id);
#elif defined(ATOMIC64)
    visit64(px, key, tri.id);
#else
    if (imageLoad(depth_keys, px).r < key) imageAtomicMax(depth_keys, px, key);
#endif
}

void main() {
    uint t = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
    if (t >= frame.info.z) return;
    Tri tri;
    if (!setup_triangle(t, tri)) return;
    if (pixels_of(tri) > BIG_PIXELS) {
#ifdef MODE_ID
        if (overflow == 0u) return;
#else
        ivec2 tiles = (tri.box.zw - tri.box.xy + TILE) / TILE;
        uint n = uint(tiles.x * tiles.y);
        // Boxes of at most CULL_TILES tiles (slivers: long thin triangles cross few of their
        // box's tiles) get jobs only for the tiles the triangle may cover: the tile pass's own
        // corner test, done here once instead of a job per tile.
        // covered[k / 32] bit k % 32: tile k (row-major in the box) may be covered.
        bool cull = n <= CULL_TILES;
        uint covered[(CULL_TILES + 31u) / 32u];
        if (cull) {
            n = 0u;
            for (uint w = 0u; w < (CULL_TILES + 31u) / 32u; ++w) covered[w] = 0u;
            uint tile = 0u;
            for (int ty = 0; ty < tiles.y; ++ty)
                for (int tx = 0; tx < tiles.x; ++tx, ++tile)
                    if (tile_may_cover(tri, ivec2(tx, ty))) { covered[tile >> 5] |= 1u << (tile & 31u); ++n; }
            if (n == 0u) return;  // no pixel centre covered
        }
        uint rec = atomicAdd(tri_count, 1u);  // a record slot past the capacity is never written
        if (rec < TRI_CAPACITY) {
            uint first = atomicAdd(job_count, n);
            if (first + n <= JOB_CAPACITY) {
                records[rec] = pack_tri(tri);
                uint k = first, tile = 0u;
                for (int ty = 0; ty < tiles.y; ++ty)
                    for (int tx = 0; tx < tiles.x; ++tx, ++tile)
                        if (!cull || (covered[tile >> 5] & (1u << (tile & 31u))) != 0u)
                            jobs[k++] = uvec2(rec, (uint(ty) << 16) | uint(tx));
                atomicMax(args.groups, (first + n + JOBS_PER_GROUP - 1u) / JOBS_PER_GROUP);
                return;
            }
            atomicAdd(job_count, 0u - n);
        }
        atomicOr(overflow, 1u);
#endif
    }
    for (int y = tri.box.y; y <= tri.box.w; ++y)
        for (int x = tri.box.x; x <= tri.box.z; ++x) visit(tri, ivec2(x, y));
}
