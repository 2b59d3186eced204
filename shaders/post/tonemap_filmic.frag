#version 460
// Hable / Uncharted 2 filmic tonemap (passes/tonemap_ref.py); linear out, the sRGB attachment encodes.
#extension GL_GOOGLE_include_directive : require
#include "post/common.glsl"

layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 color;
#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
layout(set = 0, binding = 0) uniform sampler2DArray hdr;  // views=2: one layer per eye
layout(location = 1) flat in int in_layer;               // lib/fullscreen.vert FULLSCREEN_LAYERS: the eye
#define HDR_TEXEL(p) texelFetch(hdr, ivec3(p, in_layer), 0)
#else
layout(set = 0, binding = 0) uniform sampler2D hdr;
#define HDR_TEXEL(p) texelFetch(hdr, p, 0)
#endif
layout(push_constant) uniform Push {
    float exposure;
    float inv_white_mapped;  // 1 / hable(white)
} pc;

const float A = 0.15, B = 0.50, C = 0.10, D = 0.20, E = 0.02, F = 0.30;
const float X_CAP = 1e8;

vec3 hable(vec3 x) {
    return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
}

void main() {
    vec3 raw = HDR_TEXEL(ivec2(gl_FragCoord.xy)).rgb;
    bool nan_texel = any_nan(raw);
    vec3 c = sanitize(raw, 3.0e38);  // NaN texel -> 0, negatives/-Inf -> 0, +Inf -> 3e38 (white below)
    vec3 x = min(c * pc.exposure, vec3(X_CAP));
    vec3 mapped = clamp(hable(x) * pc.inv_white_mapped, 0.0, 1.0);
    if (!nan_texel) {
        mapped = vec3(is_pos_inf(raw.r) ? 1.0 : mapped.r, is_pos_inf(raw.g) ? 1.0 : mapped.g,
                      is_pos_inf(raw.b) ? 1.0 : mapped.b);
    }
    color = vec4(mapped, 1.0);
}
