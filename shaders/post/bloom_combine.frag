#version 460
// Adds intensity * bilinear(bloom) to hdr through additive blending (passes/bloom_ref.py: combine).
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 hdr;
#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
// views=2: hdr is a layered framebuffer drawn one instance per layer (lib/fullscreen.vert
// FULLSCREEN_LAYERS), bloom a 2D array with a layer per eye: this fragment's layer
layout(set = 0, binding = 0) uniform sampler2DArray bloom;
layout(location = 1) flat in int in_layer;
#define EYE_UV(uv) vec3(uv, float(in_layer))
#else
layout(set = 0, binding = 0) uniform sampler2D bloom;
#define EYE_UV(uv) (uv)
#endif
layout(push_constant) uniform Push {
    vec2 inv_footprint;  // 1 / (factor * bloom extent): full-resolution pixels -> bloom uv
    float intensity;
} pc;

void main() {
    vec3 b = texture(bloom, EYE_UV(gl_FragCoord.xy * pc.inv_footprint)).rgb;
    hdr = vec4(pc.intensity * b, 0.0);
}
