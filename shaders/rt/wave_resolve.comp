#version 460
#extension GL_GOOGLE_include_directive : require
// Hybrid, after every tree level: the listed pixels' colours from their 64-bit fixed-point
// accumulators (wave.glsl), written into the image (hybrid_wave_shade.rgen wrote the others).
// A fixed dispatch over the capacity (groups of 64; the slots past the count return at once): the
// count is a storage read (word 3; COUNT_AT_0: classify's list, count in word 0), so it is
// synchronized as one.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, rgba16f) uniform writeonly image2D color_out;
layout(set = 0, binding = 1, r32ui) uniform readonly uimage2D ray_list;
layout(set = 0, binding = 2, std430) readonly buffer PixelArgs { uint groups; uint gy; uint gz; uint count; } pixels;
layout(set = 0, binding = 3, std430) readonly buffer Accum { uint64_t acc[]; };
layout(push_constant) uniform P { uint width; } pc;

void main() {
    uint slot = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
#ifdef COUNT_AT_0  // the list of classify.comp: (count, 1, 1); a fixed dispatch over the capacity
    if (slot >= min(pixels.groups, PIXEL_CAPACITY)) return;
#else
    if (slot >= min(pixels.count, PIXEL_CAPACITY)) return;
#endif
    uint packed = imageLoad(ray_list, ivec2(slot % pc.width, slot / pc.width)).r;
    vec3 c = vec3(float(acc[3u * slot]), float(acc[3u * slot + 1u]), float(acc[3u * slot + 2u])) * (1.0 / 4294967296.0);
    imageStore(color_out, ivec2(packed & 0xFFFFu, packed >> 16), vec4(c, 1.0));
}
