#version 460
#extension GL_GOOGLE_include_directive : require
#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
// views=2 (passes/forward.py, multiview): this eye's camera position and its layer of `ao`.
#extension GL_EXT_multiview : require
#define FORWARD_STEREO 1
#define EYE scene_eye(uint(gl_ViewIndex))
#else
#define FORWARD_STEREO 0
#endif
// Forward PBR: GGX direct lighting (directional with PCF shadows, point, spot), split-sum IBL, AO.
// Set 0: the scene (scene.glsl); set 1: this pass. Defines (passes/forward.py):
// LOC_DIFFUSE/LOC_SPECULAR/LOC_NORMAL_SSS, LIGHT_COUNT, ENV_MIPS, HAS_AO, HAS_SHADOWS,
// PCF_TAPS, IBL_INTENSITY, AO_COMBINE; CLUSTERED (with the defines of clustered/clusters.glsl,
// ALL_LIGHTS and LIST_BITMASK): shade the froxel's lights from light_grid/light_indices.
#include "scene/scene.glsl"
#include "forward/brdf.glsl"
#include "ibl/environment.glsl"
#if HAS_SHADOWS
#include "scene/shadow.glsl"
#endif

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) flat in uint in_material;

layout(location = LOC_DIFFUSE) out vec4 out_diffuse;
layout(location = LOC_SPECULAR) out vec4 out_specular;
layout(location = LOC_NORMAL_SSS) out vec4 out_normal_sss;

#if CLUSTERED
// Clustered (passes/clustered.py): `lights` as a storage buffer (any count), the froxel lists.
layout(set = 1, binding = 0, std430) readonly buffer LightsBlock { Light lights[]; };
layout(set = 1, binding = 5, rgba32ui) uniform readonly uimage2DArray light_grid;
layout(set = 1, binding = 6, std430) readonly buffer Indices { uint indices[]; };
#include "clustered/clusters.glsl"
#else
layout(set = 1, binding = 0, std140) uniform LightsBlock { Light lights[LIGHT_COUNT]; };
#endif
layout(set = 1, binding = 1) uniform sampler2D brdf_lut;
layout(set = 1, binding = 2) uniform sampler2D env_map;
#if HAS_AO
#if FORWARD_STEREO
layout(set = 1, binding = 3) uniform sampler2DArray ao_map;  // a layer per eye
#else
layout(set = 1, binding = 3) uniform sampler2D ao_map;
#endif
#endif
#if HAS_SHADOWS
layout(set = 1, binding = 4) uniform sampler2DArray shadow_maps;
#endif

// Point and spot falloff (light_window: inverse square windowed to 0 at the radius, Karis 2013;
// inv_r2 = Light.view.w) and spot cones (spot_factor): clustered/lights.glsl.
#include "clustered/lights.glsl"

// Adds light i's reflected radiance at this fragment.
void add_light(int i, Surface s, inout vec3 diffuse, inout vec3 specular) {
    Light light = lights[i];
    int type = int(light.to_light.w + 0.5);
    vec3 l;
    vec3 radiance = light.radiance.rgb;
    if (type == LIGHT_DIRECTIONAL) {
        l = safe_normalize(light.to_light.xyz, s.n);
#if HAS_SHADOWS
        int layer = int(floor(light.radiance.w + 0.5));
        if (layer >= 0 && layer < frame.counts.y) {
            radiance *= shadow_pcf(shadow_maps, in_world, layer, PCF_TAPS);
        }
#endif
    } else {
        vec3 d = light.position.xyz - in_world;
        float dist2 = dot(d, d);
        l = safe_normalize(d, s.n);
        radiance *= light_window(dist2, light.view.w);
        if (type == LIGHT_SPOT) {
            radiance *= spot_factor(dot(l, light.to_light.xyz), scene_lights[i].direction.w, scene_lights[i].radiance.w);
        }
    }
    eval_light(s, l, radiance, diffuse, specular);
}

void main() {
#if FORWARD_STEREO
    vec3 to_view = EYE - in_world;  // this eye's position (camera-relative)
#else
    vec3 to_view = -in_world;  // the camera is at the origin
#endif
    // Geometric normal from screen derivatives (the fallback for a zero shading normal), facing the viewer.
    vec3 geo = cross(dFdx(in_world), dFdy(in_world));
    geo = dot(geo, to_view) < 0.0 ? -geo : geo;
    vec3 n_in = gl_FrontFacing ? in_normal : -in_normal;  // two-sided when the prepass culls nothing
    Material m = materials[in_material];
    Surface s = make_surface(n_in, to_view, geo, m.base_color.rgb, m.surface.x, m.surface.y);

    vec3 diffuse = vec3(0.0);
    vec3 specular = vec3(0.0);
#if CLUSTERED
    int count = frame.counts.x;
#if ALL_LIGHTS
    for (int i = 0; i < count; ++i) add_light(i, s, diffuse, specular);
#else
#if FORWARD_STEREO
    float view_distance = -dot(vec3(frame.view[0][2], frame.view[1][2], frame.view[2][2]), in_world - EYE);
#else
    float view_distance = -dot(vec3(frame.view[0][2], frame.view[1][2], frame.view[2][2]), in_world);
#endif
    uvec4 cell = imageLoad(light_grid, cluster_of(gl_FragCoord.xy, view_distance));
    if (cell.y == CLUSTER_OVERFLOW) {
        for (int i = 0; i < count; ++i) add_light(i, s, diffuse, specular);
    } else {
#if LIST_BITMASK
        uint words = cell.y == 0u ? 0u : (uint(count) + 31u) / 32u;
        for (uint w = 0u; w < words; ++w) {
            for (uint bits = indices[cell.x + w]; bits != 0u; bits &= bits - 1u) {
                add_light(int(w * 32u + uint(findLSB(bits))), s, diffuse, specular);
            }
        }
#else
        for (uint j = 0u; j < cell.y; ++j) add_light(int(indices[cell.x + j]), s, diffuse, specular);
#endif
    }
#endif
#else
    int count = min(frame.counts.x, LIGHT_COUNT);
    for (int i = 0; i < count; ++i) add_light(i, s, diffuse, specular);
#endif

#if HAS_AO
#if FORWARD_STEREO
    float screen_ao = texture(ao_map, vec3(gl_FragCoord.xy * frame.viewport.zw, float(gl_ViewIndex))).r;
#else
    float screen_ao = texture(ao_map, gl_FragCoord.xy * frame.viewport.zw).r;
#endif
#else
    float screen_ao = 1.0;
#endif
    float ao = combine_ao(screen_ao, m.optics.z);
    vec3 r = reflect(-s.v, s.n);
    float top = float(ENV_MIPS - 1);
    vec3 prefiltered = textureLod(env_map, equirect_uv(r), s.roughness * top).rgb * IBL_INTENSITY;
    vec3 irradiance = textureLod(env_map, equirect_uv(s.n), top).rgb * IBL_INTENSITY + frame.ambient.rgb;
    vec2 lut = texture(brdf_lut, vec2(s.nov, s.roughness)).rg;
    eval_ibl(s, lut, prefiltered, irradiance, ao, diffuse, specular);
    specular += m.emissive.rgb;  // emission is not blurred by the SSS passes

    out_diffuse = vec4(hdr_clamp(diffuse), 1.0);
    out_specular = vec4(hdr_clamp(specular), 1.0);
    out_normal_sss = vec4(encode_normal(s.n), clamp(m.surface.z, 0.0, 1.0));
}
