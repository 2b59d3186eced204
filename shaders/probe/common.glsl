// Probe helpers: exact small-integer encodings (rgraph/probe/values.py mirrors these).
#ifndef RGRAPH_PROBE_COMMON
#define RGRAPH_PROBE_COMMON

float probe_srgb_to_linear(float c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

float probe_linear_to_srgb(float c) {
    return c <= 0.0031308 ? c * 12.92 : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

vec4 probe_enc_scaled(uint v, float scale) { return vec4(float(v) * scale); }

vec4 probe_enc_srgb(uint v) {
    float u = float(v) / 255.0;
    float l = probe_srgb_to_linear(u);
    return vec4(l, l, l, u);
}

uint probe_dec_scaled(float x, float inv_scale) { return uint(round(x * inv_scale)); }

uint probe_dec_srgb(float x) { return uint(round(probe_linear_to_srgb(x) * 255.0)); }

// Full-screen triangle corner for vertex index i (only i % 3 matters).
vec2 probe_corner(uint i) {
    uint c = i % 3u;
    return vec2(c == 1u ? 3.0 : -1.0, c == 2u ? 3.0 : -1.0);
}

#endif
