#version 460
#extension GL_GOOGLE_include_directive : require
#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
#extension GL_EXT_multiview : require
#define EYE scene_eye(uint(gl_ViewIndex))
#else
#define EYE vec3(0.0)
#endif
// Clustered forward PBR: GGX (forward/brdf.glsl) over the lights of the fragment's froxel
// (ALL_LIGHTS = 1: over every light, the reference), plus ambient * diffuse colour and emission.
// No shadows, no IBL. Writes hdr (linear radiance, clamped to HDR_MAX).
#include "scene/scene.glsl"
#include "forward/brdf.glsl"
#include "clustered/clusters.glsl"

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) flat in uint in_material;
layout(location = 0) out vec4 out_hdr;

layout(set = 1, binding = 0, std430) readonly buffer Lights { Light lights[]; };
layout(set = 1, binding = 1, rgba32ui) uniform readonly uimage2DArray light_grid;
layout(set = 1, binding = 2, std430) readonly buffer Indices { uint indices[]; };
layout(push_constant) uniform Push { uint capacity; uint light_count; } pc;

#include "clustered/lights.glsl"

void main() {
    vec3 to_view = EYE - in_world;  // views=2: this eye's position (camera-relative)
    vec3 geo = cross(dFdx(in_world), dFdy(in_world));
    geo = dot(geo, to_view) < 0.0 ? -geo : geo;
    vec3 n_in = gl_FrontFacing ? in_normal : -in_normal;
    Material m = materials[in_material];
    Surface s = make_surface(n_in, to_view, geo, m.base_color.rgb, m.surface.x, m.surface.y);
    vec3 diffuse = vec3(0.0), specular = vec3(0.0);
    uint n = pc.light_count;
#if ALL_LIGHTS
    for (uint i = 0u; i < n; ++i) shade_light(i, s, in_world, diffuse, specular);
#else
    float view_distance = -dot(vec3(frame.view[0][2], frame.view[1][2], frame.view[2][2]), in_world - EYE);
    uvec4 cell = imageLoad(light_grid, cluster_of(gl_FragCoord.xy, view_distance));
    if (cell.y == CLUSTER_OVERFLOW) {
        for (uint i = 0u; i < n; ++i) shade_light(i, s, in_world, diffuse, specular);
    } else {
#if LIST_BITMASK
        uint words = cell.y == 0u ? 0u : (n + 31u) / 32u;
        for (uint w = 0u; w < words; ++w) {
            uint bits = indices[cell.x + w];
            while (bits != 0u) {
                uint b = uint(findLSB(bits));
                bits &= bits - 1u;
                shade_light(w * 32u + b, s, in_world, diffuse, specular);
            }
        }
#else
        for (uint j = 0u; j < cell.y; ++j) shade_light(indices[cell.x + j], s, in_world, diffuse, specular);
#endif
    }
#endif
    vec3 c = diffuse + specular + s.diffuse_color * frame.ambient.rgb + m.emissive.rgb;
    out_hdr = vec4(hdr_clamp(c), 1.0);
}
