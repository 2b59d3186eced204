#version 460
// Compute probe: storage image, UBO, read-only SSBO, push constants, spec constants.
#include "tonemap.glsl"

#ifndef SSS_SAMPLES
#define SSS_SAMPLES 4
#endif

layout(local_size_x_id = 0, local_size_y = 8, local_size_z = 1) in;
layout(constant_id = 1) const float SCALE = 2.5;
layout(constant_id = 2) const bool USE_TINT = true;
layout(constant_id = 3) const int TAPS = -3;

layout(set = 0, binding = 0, rgba8) uniform writeonly image2D out_image;
layout(set = 0, binding = 1) uniform Params {
    vec4 color;
    float offsets[2];   // std140: ArrayStride 16
    mat4 model;
} params;
layout(set = 1, binding = 2, std430) readonly buffer Samples {
    uint count;
    vec4 values[];
} samples;
layout(set = 1, binding = 3, rgba32f) uniform image2D history;

layout(push_constant) uniform Push {
    vec3 tint;          // 0..12
    float exposure;     // 12..16
    mat4 view;          // 16..80
    vec4 weights[3];    // 80..128
    float radii[2];     // 128..136 (std430 stride 4)
    mat3 basis;         // 144..192 (columns padded to 16)
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    vec3 c = params.color.rgb * SCALE + params.offsets[1] + params.model[0].xyz;
    for (int i = 0; i < SSS_SAMPLES; ++i) c += samples.values[i % samples.count].rgb;
    if (USE_TINT) c *= pc.tint + pc.basis[2] * pc.radii[1] + pc.weights[2].xyz * float(TAPS);
    c += (pc.view * vec4(c, 1.0)).xyz;
    c += imageLoad(history, p).rgb;
    imageStore(out_image, p, vec4(tonemap(c, pc.exposure), 1.0));
}
