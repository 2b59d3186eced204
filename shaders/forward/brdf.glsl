// GGX Cook-Torrance BRDF shared by the forward pass, its BRDF test pass and the IBL passes.
// NumPy float64 twin: passes/forward_ref.py (keep the two in step, constant for constant).
//
// Robustness rules (the hard cases of issue 5):
// - perceptual roughness is clamped to [MIN_ROUGHNESS, 1] before alpha = roughness^2, so a
//   roughness-0 highlight is finite (peak D = 1 / (pi * alpha^2) ~ 7.9e4);
// - N.V is clamped to [MIN_N_DOT_V, 1]: grazing and slightly back-facing interpolated normals
//   shade like a grazing view instead of dividing by zero or going negative;
// - safe_normalize() of a (near-)zero vector returns the given fallback, never NaN;
// - D uses 1 - (N.H)^2 from |N x H|^2 (no cancellation near N.H = 1, Filament's form);
// - outputs are clamped to [0, HDR_MAX] so they stay finite in r16g16b16a16_sfloat.
// No tangent frame is built here: the forward pass has no normal maps and no anisotropy.
#ifndef FORWARD_BRDF_GLSL
#define FORWARD_BRDF_GLSL

const float PI = 3.14159265358979323846;
const float MIN_ROUGHNESS = 0.045;      // perceptual; alpha >= 0.002025
const float MIN_N_DOT_V = 1e-4;
const float HDR_MAX = 60000.0;          // below the float16 maximum 65504
const float NORMALIZE_EPS2 = 1e-20;     // squared length under which a vector counts as zero

vec3 safe_normalize(vec3 v, vec3 fallback) {
    float len2 = dot(v, v);
    return len2 > NORMALIZE_EPS2 ? v * inversesqrt(len2) : fallback;
}

float ggx_alpha(float perceptual_roughness) {
    float r = clamp(perceptual_roughness, MIN_ROUGHNESS, 1.0);
    return r * r;
}

// GGX / Trowbridge-Reitz normal distribution; one_minus_noh2 = |N x H|^2. For unit N, H the
// denominator is >= alpha^2 (its value at N.H = 1); the max() keeps that bound, so D <= the peak
// 1 / (pi alpha^2) even for H ~ -N, where the clamped N.H and |N x H|^2 disagree.
float d_ggx(float noh, float one_minus_noh2, float alpha) {
    float a = noh * alpha;
    float k = alpha / max(one_minus_noh2 + a * a, alpha * alpha);
    return k * k * (1.0 / PI);
}

// Smith height-correlated visibility V = G / (4 N.L N.V) (Heitz 2014).
float v_smith_ggx_correlated(float nov, float nol, float alpha) {
    float a2 = alpha * alpha;
    float gv = nol * sqrt(nov * nov * (1.0 - a2) + a2);
    float gl = nov * sqrt(nol * nol * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-12);
}

vec3 f_schlick(vec3 f0, float voh) {
    float x = 1.0 - voh;
    float x2 = x * x;
    return f0 + (1.0 - f0) * (x2 * x2 * x);
}

// Lagarde & de Rousiers 2014: specular occlusion from ambient occlusion.
float specular_occlusion(float nov, float ao, float perceptual_roughness) {
    float r = clamp(perceptual_roughness, MIN_ROUGHNESS, 1.0);
    return clamp(pow(nov + ao, exp2(-16.0 * r - 1.0)) - 1.0 + ao, 0.0, 1.0);
}

struct Surface {
    vec3 n;             // unit shading normal
    vec3 v;             // unit direction to the viewer
    float nov;          // clamped N.V
    vec3 diffuse_color; // base * (1 - metallic)
    vec3 f0;            // mix(0.04, base, metallic)
    float roughness;    // clamped perceptual roughness
    float alpha;
};

Surface make_surface(vec3 normal, vec3 to_view, vec3 fallback_normal, vec3 base_color, float roughness,
                     float metallic) {
    Surface s;
    s.v = safe_normalize(to_view, vec3(0.0, 0.0, 1.0));
    s.n = safe_normalize(normal, safe_normalize(fallback_normal, s.v));
    s.nov = clamp(dot(s.n, s.v), MIN_N_DOT_V, 1.0);
    float m = clamp(metallic, 0.0, 1.0);
    vec3 base = clamp(base_color, 0.0, 1.0);
    s.diffuse_color = base * (1.0 - m);
    s.f0 = mix(vec3(0.04), base, m);
    s.roughness = clamp(roughness, MIN_ROUGHNESS, 1.0);
    s.alpha = s.roughness * s.roughness;
    return s;
}

// Adds one light's reflected radiance (Lambert diffuse, GGX specular); l is unit, toward the light.
void eval_light(Surface s, vec3 l, vec3 radiance, inout vec3 diffuse, inout vec3 specular) {
    float nol = dot(s.n, l);
    if (!(nol > 0.0)) return;
    nol = min(nol, 1.0);
    vec3 h = safe_normalize(s.v + l, s.n);
    float noh = clamp(dot(s.n, h), 0.0, 1.0);
    vec3 nxh = cross(s.n, h);
    float voh = clamp(dot(s.v, h), 0.0, 1.0);
    float d = d_ggx(noh, dot(nxh, nxh), s.alpha);
    float vis = v_smith_ggx_correlated(s.nov, nol, s.alpha);
    vec3 f = f_schlick(s.f0, voh);
    specular += (d * vis * nol) * f * radiance;
    diffuse += s.diffuse_color * (nol / PI) * radiance;
}

// Split-sum image-based lighting: lut = (A, B) of the BRDF LUT at (N.V, roughness),
// prefiltered = env radiance prefiltered at this roughness along R, irradiance = the
// roughness-1 level along N (the diffuse estimate), ao = combined ambient occlusion.
void eval_ibl(Surface s, vec2 lut, vec3 prefiltered, vec3 irradiance, float ao, inout vec3 diffuse,
              inout vec3 specular) {
    diffuse += s.diffuse_color * irradiance * ao;
    specular += prefiltered * (s.f0 * lut.x + lut.y) * specular_occlusion(s.nov, ao, s.roughness);
}

vec3 hdr_clamp(vec3 c) {
    return clamp(c, vec3(0.0), vec3(HDR_MAX));
}

// AO_COMBINE: 0 = min (default, Frostbite), 1 = max, 2 = multiply.
#ifndef AO_COMBINE
#define AO_COMBINE 0
#endif
float combine_ao(float screen_ao, float baked_ao) {
#if AO_COMBINE == 1
    return clamp(max(screen_ao, baked_ao), 0.0, 1.0);
#elif AO_COMBINE == 2
    return clamp(screen_ao * baked_ao, 0.0, 1.0);
#else
    return clamp(min(screen_ao, baked_ao), 0.0, 1.0);
#endif
}

// normal_sss.rgb: the world-space (camera-relative axes) unit normal as 0.5 * n + 0.5.
vec3 encode_normal(vec3 n) { return 0.5 * n + 0.5; }

#endif
