// Shared rules of the post passes (see passes/post_common_ref.py). Non-finite tests use the
// bit pattern, so they hold even where the compiler may assume floats are finite.
#ifndef POST_COMMON_GLSL
#define POST_COMMON_GLSL

const float HALF_MAX = 65504.0;
const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);  // Rec. 709

bool is_nan(float x) {
    uint b = floatBitsToUint(x);
    return (b & 0x7f800000u) == 0x7f800000u && (b & 0x007fffffu) != 0u;
}

bool is_pos_inf(float x) { return floatBitsToUint(x) == 0x7f800000u; }

bool is_finite(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }

bool any_nan(vec3 c) { return is_nan(c.r) || is_nan(c.g) || is_nan(c.b); }

// NaN texel -> black; each channel: negative and -Inf -> 0, +Inf and above hi -> hi.
float sanitize1(float x, float hi) {
    if (is_pos_inf(x)) return hi;
    if (!is_finite(x)) return 0.0;  // -Inf (NaN texels are handled by the caller)
    return clamp(x, 0.0, hi);
}

vec3 sanitize(vec3 c, float hi) {
    if (any_nan(c)) return vec3(0.0);
    return vec3(sanitize1(c.r, hi), sanitize1(c.g, hi), sanitize1(c.b, hi));
}

#endif
