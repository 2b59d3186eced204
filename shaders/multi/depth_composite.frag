#version 460
// Sort-last composite (rgraph.multi.depth_composite): another device's depth and colours at this
// pixel; the pipeline's depth test (reversed-Z GREATER) keeps them only where they are nearer.
layout(set = 0, binding = 0) uniform sampler2D remote_depth;
#if COLORS > 0
layout(set = 0, binding = 1) uniform sampler2D remote0;
layout(location = 0) out vec4 out0;
#endif
#if COLORS > 1
layout(set = 0, binding = 2) uniform sampler2D remote1;
layout(location = 1) out vec4 out1;
#endif
#if COLORS > 2
layout(set = 0, binding = 3) uniform sampler2D remote2;
layout(location = 2) out vec4 out2;
#endif
#if COLORS > 3
layout(set = 0, binding = 4) uniform sampler2D remote3;
layout(location = 3) out vec4 out3;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    gl_FragDepth = texelFetch(remote_depth, p, 0).r;
#if COLORS > 0
    out0 = texelFetch(remote0, p, 0);
#endif
#if COLORS > 1
    out1 = texelFetch(remote1, p, 0);
#endif
#if COLORS > 2
    out2 = texelFetch(remote2, p, 0);
#endif
#if COLORS > 3
    out3 = texelFetch(remote3, p, 0);
#endif
}
