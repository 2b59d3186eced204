#version 460
#extension GL_GOOGLE_include_directive : require
// Classify pixels by the material of their visible instance (visibility buffer): those that
// reflect or refract are appended to the ray list; args[0] (the indirect trace width) counts them.
#include "rt/gbuffer.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform usampler2D visibility;
layout(set = 0, binding = 1, std430) buffer Args { uint args[4]; };
layout(set = 0, binding = 2, r32ui) uniform writeonly uimage2D ray_list;
layout(set = 0, binding = 3, std430) readonly buffer Secondary { uint needs_rays[]; };  // per instance
layout(push_constant) uniform P { uvec2 size; } pc;

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= pc.size.x || px.y >= pc.size.y) return;
    uint id = texelFetch(visibility, ivec2(px), 0).r;
    if (id == 0u || needs_rays[vis_instance(id)] == 0u) return;
    uint slot = atomicAdd(args[0], 1u);
    imageStore(ray_list, ivec2(slot % pc.size.x, slot / pc.size.x), uvec4((px.y << 16) | px.x));
}
