#version 460
// Sort-last composite (rgraph.multi.depth_composite): another device's depth and colours at this
// pixel; the pipeline's depth test (reversed-Z GREATER) keeps them only where they are nearer.
// LAYERED: layered attachments in one multiview pass; view gl_ViewIndex samples its layer.
// SAMPLERn / OUTn: colour n's sampler and output types, of its format's numeric type
// ((u|i)sampler2D[Array], (u|i)vec4).
#if LAYERED
#extension GL_EXT_multiview : require
#define REMOTE sampler2DArray
#define AT(p) ivec3(p, gl_ViewIndex)
#else
#define REMOTE sampler2D
#define AT(p) p
#endif
layout(set = 0, binding = 0) uniform REMOTE remote_depth;
#if COLORS > 0
layout(set = 0, binding = 1) uniform SAMPLER0 remote0;
layout(location = 0) out OUT0 out0;
#endif
#if COLORS > 1
layout(set = 0, binding = 2) uniform SAMPLER1 remote1;
layout(location = 1) out OUT1 out1;
#endif
#if COLORS > 2
layout(set = 0, binding = 3) uniform SAMPLER2 remote2;
layout(location = 2) out OUT2 out2;
#endif
#if COLORS > 3
layout(set = 0, binding = 4) uniform SAMPLER3 remote3;
layout(location = 3) out OUT3 out3;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    gl_FragDepth = texelFetch(remote_depth, AT(p), 0).r;
#if COLORS > 0
    out0 = texelFetch(remote0, AT(p), 0);
#endif
#if COLORS > 1
    out1 = texelFetch(remote1, AT(p), 0);
#endif
#if COLORS > 2
    out2 = texelFetch(remote2, AT(p), 0);
#endif
#if COLORS > 3
    out3 = texelFetch(remote3, AT(p), 0);
#endif
}
