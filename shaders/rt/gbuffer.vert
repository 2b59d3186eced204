#version 460
#extension GL_GOOGLE_include_directive : require
// Thin G-buffer: the scene's invariant clip position, world normal, material.
#include "scene/scene_vertex.glsl"
layout(location = 0) out vec3 v_normal;
layout(location = 1) flat out uint v_material;

void main() {
    uint draw = uint(gl_InstanceIndex);
    gl_Position = scene_clip_position(in_position, draw);
    v_normal = mat3(draws[draw].normal_matrix) * in_normal;
    v_material = draws[draw].info.x;
}
