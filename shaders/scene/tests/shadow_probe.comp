#version 460
#extension GL_GOOGLE_include_directive : require
// Test-only: shadow_pcf of both shadow layers at each visible pixel's world position
// (reconstructed from the prepass depth); r, g = lit fraction of layers 0, 1; b = depth; -1 = sky.
#include "scene/shadow.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 1, binding = 0) uniform sampler2D depth_tex;
layout(set = 1, binding = 1) uniform sampler2DArray shadow_maps;
layout(set = 1, binding = 2, rgba32f) uniform writeonly image2D lit_out;
layout(push_constant) uniform Push { ivec4 taps; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(lit_out);
    if (any(greaterThanEqual(p, size))) {
        return;
    }
    float d = texelFetch(depth_tex, p, 0).r;
    if (d <= 0.0) {
        imageStore(lit_out, p, vec4(-1.0));
        return;
    }
    vec3 w = scene_world_from_depth((vec2(p) + 0.5) / vec2(size), d);
    imageStore(lit_out, p, vec4(shadow_pcf(shadow_maps, w, 0, pc.taps.x), shadow_pcf(shadow_maps, w, 1, pc.taps.x), d, 1.0));
}
