#version 460
#extension GL_GOOGLE_include_directive : require
// Visibility buffer: the scene's invariant clip position (positions only) and the draw index
// (= the TLAS instance index: one draw per instance, mesh-major, as passes/raytrace_standalone.py).
#define SCENE_POSITION_ONLY
#include "scene/scene_vertex.glsl"
layout(location = 0) flat out uint v_draw;

void main() {
    uint draw = uint(gl_InstanceIndex);
    gl_Position = scene_clip_position(scene_vertex_position(in_position, draw), draw);
    v_draw = draw;
}
