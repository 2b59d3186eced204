#version 460
// Horizon-based ambient occlusion (Bavoil and Sainz 2008) on working-resolution depth.
// The NumPy reference passes/hbao_ref.py:hbao documents every step; keep them in sync.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

#ifndef DIRECTIONS
#define DIRECTIONS 8
#endif
#ifndef STEPS
#define STEPS 4
#endif

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform HBAO_SAMPLER depth_quarter;
layout(set = 0, binding = 1, r8) uniform writeonly HBAO_IMAGE ao_quarter;
layout(push_constant) uniform Push {
    vec4 proj;   // P00, P11, near, -
    vec4 knobs;  // radius (world), angle bias (rad), strength, max radius (working-res px)
} pc;

const float PI = 3.14159265358979;
const float BAYER[16] = float[16](0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5);

ivec2 qsize;

float fetch(ivec2 p) { return texelFetch(depth_quarter, EYE(p), 0).r; }

vec3 pos_at(ivec2 p, float d) { return view_position(d, (vec2(p) + 0.5) / vec2(qsize), pc.proj); }

vec3 axis_diff(ivec2 q, vec3 p, ivec2 step, vec3 fallback) {
    bool found = false;
    vec3 best = fallback;
    for (int sgn = 1; sgn >= -1; sgn -= 2) {
        ivec2 n = q + sgn * step;
        if (any(lessThan(n, ivec2(0))) || any(greaterThanEqual(n, qsize))) continue;
        float d = fetch(n);
        if (d <= 0.0) continue;
        vec3 diff = (pos_at(n, d) - p) * float(sgn);
        if (!found || abs(diff.z) < abs(best.z)) { best = diff; found = true; }
    }
    return best;
}

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    qsize = XY(textureSize(depth_quarter, 0));
    if (any(greaterThanEqual(q, qsize))) return;
    float d = fetch(q);
    if (d <= 0.0) { imageStore(ao_quarter, EYE(q), vec4(1.0)); return; }  // sky: no occlusion
    vec3 p = pos_at(q, d);
    vec3 ddx = axis_diff(q, p, ivec2(1, 0), vec3(1, 0, 0));
    vec3 ddy = axis_diff(q, p, ivec2(0, 1), vec3(0, -1, 0));
    vec3 n = cross(ddy, ddx);
    float len = length(n);
    n = len < 1e-30 ? vec3(0, 0, 1) : n / len;
    if (dot(n, p) > 0.0) n = -n;  // face the camera (V = -p), also for walls seen edge-on
    float sin_bias = sin(pc.knobs.y);

    float radius = pc.knobs.x;
    float r2max = radius * radius;
    float radius_px = min(radius * pc.proj.x * float(qsize.x) * 0.5 / -p.z, pc.knobs.w);
    float stp = max(radius_px / float(STEPS + 1), 1.0);
    float rot = BAYER[(q.y & 3) * 4 + (q.x & 3)] / 16.0;
    float jitter = BAYER[((q.y + 2) & 3) * 4 + ((q.x + 1) & 3)] / 16.0;
    float total = 0.0;
    for (int k = 0; k < DIRECTIONS; ++k) {
        float theta = 2.0 * PI * (float(k) + rot) / float(DIRECTIONS);
        vec2 dir = vec2(cos(theta), sin(theta));
        float sin_h = sin_bias;
        float ray = jitter * stp + 1.0;
        float acc = 0.0;
        for (int s = 0; s < STEPS; ++s) {
            ivec2 t = ivec2(floor(vec2(q) + 0.5 + ray * dir));
            ray += stp;
            if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, qsize))) break;
            float ds = fetch(t);
            if (ds <= 0.0) continue;  // sky never occludes
            vec3 v = pos_at(t, ds) - p;
            float r2 = dot(v, v);
            if (r2 >= r2max || r2 < 1e-20) continue;
            float sin_s = dot(n, v) * inversesqrt(r2);
            if (sin_s > sin_h) {
                acc += (1.0 - r2 / r2max) * (sin_s - sin_h);
                sin_h = sin_s;
            }
        }
        total += acc;
    }
    imageStore(ao_quarter, EYE(q), vec4(clamp(1.0 - pc.knobs.z * total / float(DIRECTIONS), 0.0, 1.0)));
}
