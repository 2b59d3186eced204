#version 460
#if FULLSCREEN_LAYERS > 1
#extension GL_ARB_shader_viewport_layer_array : require
#endif
// A full-screen triangle: draw 3 vertices, no vertex buffer. uv covers [0,1]^2 over the viewport.
layout(location = 0) out vec2 out_uv;
#if FULLSCREEN_LAYERS > 1
// FULLSCREEN_LAYERS = n: one instance per layer of a layered framebuffer (gl_Layer from the
// vertex shader, Vulkan 1.2 shaderOutputLayer); the layer for the fragment shader
layout(location = 1) flat out int out_layer;
#endif

void main() {
    vec2 uv = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
    out_uv = uv;
#if FULLSCREEN_LAYERS > 1
    gl_Layer = gl_InstanceIndex;
    out_layer = gl_InstanceIndex;
#endif
    gl_Position = vec4(uv * 2.0 - 1.0, 0.0, 1.0);
}
