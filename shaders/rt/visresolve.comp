#version 460
#extension GL_GOOGLE_include_directive : require
// Compute visibility buffer, 64-bit path (ATOMIC64 of rt/visraster.comp): the ids are the low 32
// bits of the packed (key << 32 | id) per pixel, 0 where nothing was rasterized.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 6, r32ui) uniform writeonly uimage2D visibility;
layout(set = 0, binding = 15, std430) readonly buffer VisKeys { uint64_t vis_keys[]; };

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy), size = imageSize(visibility);
    if (any(greaterThanEqual(px, size))) return;
    imageStore(visibility, px, uvec4(uint(vis_keys[px.y * size.x + px.x] & 0xFFFFFFFFul)));
}
