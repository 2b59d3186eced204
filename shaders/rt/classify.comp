#version 460
#extension GL_GOOGLE_include_directive : require
// Classify pixels by the material of their visible instance (visibility buffer): those that
// reflect or refract are appended to the ray list; args[0] (the indirect trace width) counts them.
// One global atomic per 8x8 tile reserves a contiguous range, filled in row-major order within
// the tile, so neighbouring launch slots of the secondary trace are neighbouring pixels
// (coherent rays per warp) and the list is deterministic within each tile.
#include "rt/gbuffer.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform usampler2D visibility;
layout(set = 0, binding = 1, std430) buffer Args { uint args[4]; };
layout(set = 0, binding = 2, r32ui) uniform writeonly uimage2D ray_list;
layout(set = 0, binding = 3, std430) readonly buffer Secondary { uint needs_rays[]; };  // per instance
layout(push_constant) uniform P { uvec2 size; } pc;

shared uint flags[64];
shared uint base;

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    uint lid = gl_LocalInvocationIndex;
    bool inside = px.x < pc.size.x && px.y < pc.size.y;
    uint id = inside ? texelFetch(visibility, ivec2(px), 0).r : 0u;
    bool needs = id != 0u && needs_rays[vis_instance(id)] != 0u;
    flags[lid] = needs ? 1u : 0u;
    barrier();
    uint before = 0u, total = 0u;
    for (uint j = 0u; j < 64u; ++j) { uint f = flags[j]; before += j < lid ? f : 0u; total += f; }
    if (lid == 0u && total > 0u) base = atomicAdd(args[0], total);
    barrier();
    if (!needs) return;
    uint slot = base + before;
    imageStore(ray_list, ivec2(slot % pc.size.x, slot / pc.size.x), uvec4((px.y << 16) | px.x));
}
