#version 460
// Classify pixels by material (G-buffer): those with reflective or refractive materials are
// appended to the ray list; args[0] (the indirect trace width) counts them.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform usampler2D material_ids;
layout(set = 0, binding = 1, std430) buffer Args { uint args[4]; };
layout(set = 0, binding = 2, r32ui) uniform writeonly uimage2D ray_list;
layout(set = 0, binding = 3, std430) readonly buffer Secondary { uint needs_rays[]; };  // per material
layout(push_constant) uniform P { uvec2 size; } pc;

void main() {
    uvec2 px = gl_GlobalInvocationID.xy;
    if (px.x >= pc.size.x || px.y >= pc.size.y) return;
    uint id = texelFetch(material_ids, ivec2(px), 0).r;
    if (id == 0u || needs_rays[id - 1u] == 0u) return;
    uint slot = atomicAdd(args[0], 1u);
    imageStore(ray_list, ivec2(slot % pc.size.x, slot / pc.size.x), uvec4((px.y << 16) | px.x));
}
