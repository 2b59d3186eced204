// Shadow lookups for the maps written by the shadow_map pass (include after scene.glsl or alone).
//
//   #include "scene/shadow.glsl"
//   float lit = shadow_pcf(shadow_maps, world_cam_rel, layer, taps);   // 1 lit, 0 in shadow
//
// Convention: layer k of `shadow_maps` holds shadow light k (the k-th directional light with
// `shadows: true`, in scene order; Light.radiance.w and frame.sun_direction.w carry it, -1 = none).
// frame.shadow_view_proj[k] maps camera-relative world to the light's orthographic clip space;
// uv = ndc.xy * 0.5 + 0.5 (no Y flip); depth is REVERSED: 1 nearest the light, 0 farthest, the
// map is cleared to 0 (nothing) and keeps the largest depth. A point is lit when its depth is
// >= the stored depth (the pass already applies a depth bias pushing stored depths away from
// the light; SHADOW_EPSILON adds a little more). Outside the light's box: lit.
//
// PCF: `taps` is rounded to an n x n grid (n = round(sqrt(taps)), 1 -> one tap, 16 -> 4x4),
// one texel apart and centred on the point; the result is the lit fraction.
// Two variants: a plain sampler2DArray (bind with the "nearest" sampler; manual compare), or a
// sampler2DArrayShadow whose sampler has compareEnable and compareOp GREATER_OR_EQUAL
// (hardware compare; with a LINEAR compare sampler each tap is itself bilinear PCF).

#ifndef RGRAPH_SHADOW_GLSL
#define RGRAPH_SHADOW_GLSL

#include "scene/scene.glsl"

#ifndef SHADOW_EPSILON
#define SHADOW_EPSILON 1e-5
#endif

// Light-space (uv, reversed depth) of a camera-relative world point; false outside the box.
bool shadow_coords(vec3 world_cam_rel, int layer, out vec3 uvz) {
    vec4 clip = frame.shadow_view_proj[layer] * vec4(world_cam_rel, 1.0);
    vec3 ndc = clip.xyz / clip.w;
    uvz = vec3(ndc.xy * 0.5 + 0.5, ndc.z);
    return all(greaterThanEqual(uvz, vec3(0.0))) && all(lessThanEqual(uvz, vec3(1.0)));
}

int shadow_grid(int taps) {
    return max(1, int(round(sqrt(float(max(taps, 1))))));
}

float shadow_pcf(sampler2DArray maps, vec3 world_cam_rel, int layer, int taps) {
    vec3 uvz;
    if (layer < 0 || !shadow_coords(world_cam_rel, layer, uvz)) {
        return 1.0;
    }
    vec2 texel = 1.0 / vec2(textureSize(maps, 0).xy);
    int n = shadow_grid(taps);
    float lit = 0.0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            vec2 offset = (vec2(i, j) - 0.5 * float(n - 1)) * texel;
            float stored = textureLod(maps, vec3(uvz.xy + offset, float(layer)), 0.0).r;
            lit += uvz.z + SHADOW_EPSILON >= stored ? 1.0 : 0.0;
        }
    }
    return lit / float(n * n);
}

float shadow_pcf(sampler2DArrayShadow maps, vec3 world_cam_rel, int layer, int taps) {
    vec3 uvz;
    if (layer < 0 || !shadow_coords(world_cam_rel, layer, uvz)) {
        return 1.0;
    }
    vec2 texel = 1.0 / vec2(textureSize(maps, 0).xy);
    int n = shadow_grid(taps);
    float lit = 0.0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            vec2 offset = (vec2(i, j) - 0.5 * float(n - 1)) * texel;
            lit += texture(maps, vec4(uvz.xy + offset, float(layer), uvz.z + SHADOW_EPSILON));
        }
    }
    return lit / float(n * n);
}

#endif
