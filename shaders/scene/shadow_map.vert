#version 460
#extension GL_GOOGLE_include_directive : require
#ifdef SHADOW_LAYERED
#extension GL_ARB_shader_viewport_layer_array : require
#endif
// Shadow map: one pipeline for every layer; the light and the framebuffer layer by push constant.
// SHADOW_LAYERED: the framebuffer has several layers (a one-layer framebuffer leaves gl_Layer
// unwritten: the validation layer warns on any write there).
#define SCENE_POSITION_ONLY
#include "scene/scene_vertex.glsl"

layout(push_constant) uniform Push {
    ivec4 shadow;  // x: shadow light index (frame.shadow_view_proj), y: framebuffer layer
} pc;

void main() {
    uint d = uint(gl_InstanceIndex);
    gl_Position = frame.shadow_view_proj[pc.shadow.x] * scene_world_position(scene_vertex_position(in_position, d), d);
#ifdef SHADOW_LAYERED
    gl_Layer = pc.shadow.y;
#endif
}
