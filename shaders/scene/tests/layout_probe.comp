#version 460
#extension GL_GOOGLE_include_directive : require
// Test-only: fixed-size arrays of the scene structs so SPIR-V reflection reports their sizes
// (tests/test_scene_packing.py compares them with rgraph/scene/packing.py).
#include "scene/scene.glsl"
#include "scene/shadow.glsl"

layout(local_size_x = 1) in;
layout(set = 2, binding = 0, std430) buffer DrawProbe { Draw d[2]; } draw_probe;
layout(set = 2, binding = 1, std430) buffer MaterialProbe { Material m[2]; } material_probe;
layout(set = 2, binding = 2, std430) buffer SceneLightProbe { SceneLight l[2]; } scene_light_probe;
layout(set = 2, binding = 3, std430) buffer DecalProbe { Decal d[2]; } decal_probe;
layout(set = 2, binding = 4, std140) uniform LightProbe { Light l[2]; } light_probe;
layout(set = 2, binding = 5) uniform sampler2DArray shadow_plain;
layout(set = 2, binding = 6) uniform sampler2DArrayShadow shadow_compare;

void main() {
    draw_probe.d[0] = draws[0];
    material_probe.m[0] = materials[0];
    scene_light_probe.l[0] = scene_lights[0];
    decal_probe.d[0].world_to_decal = decals[0].world_to_decal * frame.view_proj * light_probe.l[1].view.x;
    decal_probe.d[1].color = vec4(shadow_pcf(shadow_plain, vec3(0.0), 0, 16), shadow_pcf(shadow_compare, vec3(0.0), 0, 4),
                                  scene_clip_position(vec3(0.0), 0u).x, scene_world_normal(vec3(0.0, 1.0, 0.0), 0u).x);
}
