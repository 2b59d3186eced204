#version 460
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 color;
layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1) uniform Tint { vec4 frame; } tint;

void main() {
    vec4 c = texelFetch(src, ivec2(gl_FragCoord.xy), 0);
    color = vec4(c.rgb, tint.frame.w);
}
