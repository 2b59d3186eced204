#version 460
// Joint bilateral upsample of quarter AO guided by full-resolution depth (see
// passes/hbao_ref.py:upsample): the 2x2 bilinear footprint weighted by
// exp(-sharpness * (rel - min rel)), rel = |z_full - z_quarter| / z_full.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform HBAO_SAMPLER ao_quarter;
layout(set = 0, binding = 1) uniform HBAO_SAMPLER depth;
layout(set = 0, binding = 2, r32f) uniform readonly HBAO_IMAGE depth_quarter;
layout(set = 0, binding = 3, r8) uniform writeonly HBAO_IMAGE ao;
layout(push_constant) uniform Push {
    vec4 proj;   // P00, P11, near, -
    vec4 knobs;  // sharpness, -, -, -
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = XY(imageSize(ao));
    if (any(greaterThanEqual(p, size))) return;
    float d = texelFetch(depth, EYE(p), 0).r;
    if (d <= 0.0) { imageStore(ao, EYE(p), vec4(1.0)); return; }
    float near = pc.proj.z;
    float zf = near / d;
    ivec2 qsize = XY(imageSize(depth_quarter));
    vec2 f = (vec2(p) + 0.5) * vec2(qsize) / vec2(size) - 0.5;
    vec2 b = floor(f);
    vec2 a = f - b;
    float wb[4], rel[4], val[4];
    bool valid[4];
    float rel_min = 1e30;
    for (int i = 0; i < 4; ++i) {
        ivec2 o = ivec2(i & 1, i >> 1);
        ivec2 t = clamp(ivec2(b) + o, ivec2(0), qsize - 1);
        float dq = imageLoad(depth_quarter, EYE(t)).r;
        wb[i] = (o.x == 1 ? a.x : 1.0 - a.x) * (o.y == 1 ? a.y : 1.0 - a.y);
        valid[i] = dq > 0.0;
        rel[i] = valid[i] ? abs(zf - near / dq) / zf : 0.0;
        val[i] = texelFetch(ao_quarter, EYE(t), 0).r;
        if (valid[i]) rel_min = min(rel_min, rel[i]);
    }
    float sum_w = 0.0, sum = 0.0;
    for (int i = 0; i < 4; ++i) {
        if (!valid[i]) continue;
        float w = wb[i] * exp(-pc.knobs.x * (rel[i] - rel_min));
        sum_w += w;
        sum += w * val[i];
    }
    imageStore(ao, EYE(p), vec4(sum_w > 0.0 ? sum / sum_w : 1.0));
}
