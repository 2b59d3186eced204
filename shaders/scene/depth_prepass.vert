#version 460
#extension GL_GOOGLE_include_directive : require
// Depth prepass: reversed-Z, infinite far plane; the shared invariant scene transform.
#define SCENE_POSITION_ONLY
#include "scene/scene_vertex.glsl"

void main() {
    uint d = uint(gl_InstanceIndex);
    gl_Position = scene_clip_position(scene_vertex_position(in_position, d), d);
}
