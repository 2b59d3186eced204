#version 460
// Adds intensity * bilinear(bloom) to hdr through additive blending (passes/bloom_ref.py: combine).
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 hdr;
layout(set = 0, binding = 0) uniform sampler2D bloom;
layout(push_constant) uniform Push {
    vec2 inv_footprint;  // 1 / (factor * bloom extent): full-resolution pixels -> bloom uv
    float intensity;
} pc;

void main() {
    vec3 b = texture(bloom, gl_FragCoord.xy * pc.inv_footprint).rgb;
    hdr = vec4(pc.intensity * b, 0.0);
}
