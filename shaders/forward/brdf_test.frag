#version 460
// FORWARD_TEST: shades one (N, V, L, roughness, metallic, AO, IBL inputs) case per pixel with
// the same brdf.glsl functions, in the same order, as forward.frag; compared against
// passes/forward_ref.shade_case. Case i = row * width + column; 8 vec4 per case.
#extension GL_GOOGLE_include_directive : require
#include "forward/brdf.glsl"

layout(location = 0) in vec2 uv;
layout(location = LOC_DIFFUSE) out vec4 out_diffuse;
layout(location = LOC_SPECULAR) out vec4 out_specular;

struct Case {
    vec4 normal;       // xyz: shading normal (may be zero, unnormalised); w: LUT A
    vec4 to_view;      // xyz: direction to the viewer (unnormalised; also the fallback normal); w: LUT B
    vec4 to_light;     // xyz: direction to the light (unnormalised; zero means N)
    vec4 radiance;     // rgb: light radiance at the surface
    vec4 base_color;
    vec4 material;     // (roughness, metallic, screen-space AO, baked AO)
    vec4 prefiltered;  // rgb: prefiltered env radiance along R
    vec4 irradiance;   // rgb: diffuse env estimate along N
};
layout(set = 0, binding = 0, std430) readonly buffer Cases { Case cases[]; };
layout(push_constant) uniform Push { uint width; uint count; } pc;

void main() {
    uvec2 p = uvec2(gl_FragCoord.xy);
    uint i = p.y * pc.width + p.x;
    if (i >= pc.count) {
        out_diffuse = vec4(0.0);
        out_specular = vec4(0.0);
        return;
    }
    Case c = cases[i];
    Surface s = make_surface(c.normal.xyz, c.to_view.xyz, c.to_view.xyz, c.base_color.rgb, c.material.x,
                             c.material.y);
    vec3 diffuse = vec3(0.0);
    vec3 specular = vec3(0.0);
    eval_light(s, safe_normalize(c.to_light.xyz, s.n), c.radiance.rgb, diffuse, specular);
    float ao = combine_ao(c.material.z, c.material.w);
    eval_ibl(s, vec2(c.normal.w, c.to_view.w), c.prefiltered.rgb, c.irradiance.rgb, ao, diffuse, specular);
    out_diffuse = vec4(hdr_clamp(diffuse), 1.0);
    out_specular = vec4(hdr_clamp(specular), 1.0);
}
