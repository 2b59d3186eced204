#version 460
#extension GL_GOOGLE_include_directive : require
// Clustered forward vertex stage: the shared invariant scene transform (matches the prepass).
#include "scene/scene_vertex.glsl"

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) flat out uint out_material;

void main() {
    uint d = uint(gl_InstanceIndex);
    out_world = scene_world_position(in_position, d).xyz;
    out_normal = mat3(draws[d].normal_matrix) * in_normal;
    out_material = draws[d].info.x;
    gl_Position = scene_clip_position(in_position, d);
}
