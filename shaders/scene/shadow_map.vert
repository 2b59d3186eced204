#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_viewport_layer_array : require
// Shadow map: one pipeline for every layer; the light and the framebuffer layer by push constant.
#define SCENE_POSITION_ONLY
#include "scene/scene_vertex.glsl"

layout(push_constant) uniform Push {
    ivec4 shadow;  // x: shadow light index (frame.shadow_view_proj), y: framebuffer layer
} pc;

void main() {
    uint d = uint(gl_InstanceIndex);
    gl_Position = frame.shadow_view_proj[pc.shadow.x] * scene_world_position(scene_vertex_position(in_position, d), d);
    gl_Layer = pc.shadow.y;
}
