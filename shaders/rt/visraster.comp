#version 460
#extension GL_GOOGLE_include_directive : require
// Compute visibility buffer, one thread per triangle (rt/visraster.glsl). MODE_ID undefined: the
// depth pass (atomicMax of the key); triangles whose box exceeds BIG_PIXELS append one job per
// TILE x TILE tile of their box for rt/vistiles.comp (a workgroup per job, so walls and floors do not
// serialize on one thread). When the job list is full (JOB_CAPACITY) the reservation is undone,
// args.overflow is set and the thread rasterizes its box itself. MODE_ID: the id pass (atomicMax
// of the id where the key equals the stored one); big triangles are left to the tile jobs unless
// the depth pass overflowed, then every big triangle is also done here (the tile jobs that did
// run write the same ids again: atomicMax is idempotent).
#include "rt/visraster.glsl"
layout(local_size_x = 64) in;
#ifdef MODE_ID
layout(set = 0, binding = 5, r32ui) uniform readonly uimage2D depth_keys;
layout(set = 0, binding = 6, r32ui) uniform uimage2D visibility;
layout(set = 0, binding = 7, std430) readonly buffer Args { uint job_count; uint job_y; uint job_z; uint overflow; } args;
#else
layout(set = 0, binding = 5, r32ui) uniform uimage2D depth_keys;
layout(set = 0, binding = 7, std430) buffer Args { uint job_count; uint job_y; uint job_z; uint overflow; } args;
layout(set = 0, binding = 8, std430) writeonly buffer Jobs { uvec2 jobs[]; };
#endif

void visit(Tri tri, ivec2 px) {
    uint key;
    if (!cover(tri, px, key)) return;
#ifdef MODE_ID
    if (imageLoad(depth_keys, px).r == key) imageAtomicMax(visibility, px, tri.id);
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
        if (args.overflow == 0u) return;
#else
        ivec4 tiles = tri.box / TILE;  // every tile of the box: a per-tile test here would run serially
        uint n = uint(tiles.z - tiles.x + 1) * uint(tiles.w - tiles.y + 1);
        uint first = atomicAdd(args.job_count, n);
        if (first + n <= JOB_CAPACITY) {
            uint k = first;
            for (int ty = tiles.y; ty <= tiles.w; ++ty)
                for (int tx = tiles.x; tx <= tiles.z; ++tx) jobs[k++] = uvec2(t, (uint(ty) << 16) | uint(tx));
            return;
        }
        // Full: undo (a reservation made while one is pending also fails, so the list stays
        // contiguous and job_count ends <= JOB_CAPACITY), flag it and rasterize here.
        atomicAdd(args.job_count, 0u - n);
        atomicOr(args.overflow, 1u);
#endif
    }
    for (int y = tri.box.y; y <= tri.box.w; ++y)
        for (int x = tri.box.x; x <= tri.box.z; ++x) visit(tri, ivec2(x, y));
}
