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
    gl_Position = frame.shadow_view_proj[pc.shadow.x] * scene_world_position(in_position, uint(gl_InstanceIndex));
    gl_Layer = pc.shadow.y;
}
