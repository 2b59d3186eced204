#version 460
// Compute visibility buffer, first pass: depth keys and ids 0 (nothing), the tile-job list's
// indirect arguments (0, 1, 1) and its overflow flag 0.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 5, r32ui) uniform writeonly uimage2D depth_keys;
layout(set = 0, binding = 6, r32ui) uniform writeonly uimage2D visibility;
layout(set = 0, binding = 7, std430) writeonly buffer Args { uint args[4]; };

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px == ivec2(0)) { args[0] = 0u; args[1] = 1u; args[2] = 1u; args[3] = 0u; }
    if (any(greaterThanEqual(px, imageSize(depth_keys)))) return;
    imageStore(depth_keys, px, uvec4(0u));
    imageStore(visibility, px, uvec4(0u));
}
