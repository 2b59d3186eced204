#version 460
#ifdef CLEAR_KEYS
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#endif
// Compute visibility buffer, first pass: depth keys and ids 0 (nothing), the tile jobs' indirect
// arguments (0, 1, 1), the job list's count and overflow flag 0; with RESET_RAYS (the pass
// writes ray_args) also the compacted ray list's arguments (0, 1, 1), saving rt_reset_rays; with
// WAVE_LEVELS n (1..3) the wavefront lists' arguments (bindings 10.., rays_1_args..) (0, 1, 1, 0);
// with CLEAR_KEYS the 64-bit path's packed keys (binding 15) 0; with RESET_FIRST the compute
// shading pass's list arguments (binding 13, first_args) (0, 1, 1, 0).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 5, r32ui) uniform writeonly uimage2D depth_keys;
layout(set = 0, binding = 6, r32ui) uniform writeonly uimage2D visibility;
layout(set = 0, binding = 7, std430) writeonly buffer Args { uint args[4]; };
layout(set = 0, binding = 8, std430) writeonly buffer Jobs { uint header[4]; };
#ifdef RESET_RAYS
layout(set = 0, binding = 9, std430) writeonly buffer RayArgs { uint ray_args[4]; };
#endif
#ifdef RESET_FIRST
layout(set = 0, binding = 13, std430) writeonly buffer FirstArgs { uint first_args[4]; };
#endif
#ifdef CLEAR_KEYS
layout(set = 0, binding = 15, std430) writeonly buffer VisKeys { uint64_t vis_keys[]; };
#endif
#if WAVE_LEVELS >= 1
layout(set = 0, binding = 10, std430) writeonly buffer Wave1 { uint wave1[4]; };
#endif
#if WAVE_LEVELS >= 2
layout(set = 0, binding = 11, std430) writeonly buffer Wave2 { uint wave2[4]; };
#endif
#if WAVE_LEVELS >= 3
layout(set = 0, binding = 12, std430) writeonly buffer Wave3 { uint wave3[4]; };
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px == ivec2(0)) {
        args[0] = 0u; args[1] = 1u; args[2] = 1u; args[3] = 0u;
        header[0] = 0u; header[1] = 0u; header[2] = 0u;
#ifdef RESET_RAYS
        ray_args[0] = 0u; ray_args[1] = 1u; ray_args[2] = 1u; ray_args[3] = 0u;
#endif
#ifdef RESET_FIRST
        first_args[0] = 0u; first_args[1] = 1u; first_args[2] = 1u; first_args[3] = 0u;
#endif
#if WAVE_LEVELS >= 1
        wave1[0] = 0u; wave1[1] = 1u; wave1[2] = 1u; wave1[3] = 0u;
#endif
#if WAVE_LEVELS >= 2
        wave2[0] = 0u; wave2[1] = 1u; wave2[2] = 1u; wave2[3] = 0u;
#endif
#if WAVE_LEVELS >= 3
        wave3[0] = 0u; wave3[1] = 1u; wave3[2] = 1u; wave3[3] = 0u;
#endif
    }
    if (any(greaterThanEqual(px, imageSize(depth_keys)))) return;
    imageStore(depth_keys, px, uvec4(0u));
    imageStore(visibility, px, uvec4(0u));
#ifdef CLEAR_KEYS
    vis_keys[px.y * imageSize(depth_keys).x + px.x] = 0ul;
#endif
}
