#version 460
#extension GL_GOOGLE_include_directive : require
// Forward PBR vertex stage: the shared invariant scene transform (bit-identical to the depth
// prepass, so the GREATER_OR_EQUAL depth_read test passes on exactly the visible surfaces).
#include "scene/scene_vertex.glsl"

layout(location = 0) out vec3 out_world;         // camera-relative world position
layout(location = 1) out vec3 out_normal;        // world normal, not renormalised
layout(location = 2) flat out uint out_material;

void main() {
    uint d = uint(gl_InstanceIndex);
    vec3 position = in_position, normal = in_normal;
    scene_vertex_pose(position, normal, d);
    out_world = scene_world_position(position, d).xyz;
    out_normal = scene_normal3(d) * normal;
    out_material = scene_info(d).x;
    gl_Position = scene_clip_position(position, d);
}
