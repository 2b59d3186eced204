#version 460
#extension GL_GOOGLE_include_directive : require
// Visibility buffer: instance and primitive of the visible triangle, nothing else.
#include "rt/gbuffer.glsl"
layout(early_fragment_tests) in;
layout(location = 0) flat in uint v_draw;
layout(location = 0) out uint o_id;

void main() { o_id = vis_encode(v_draw, uint(gl_PrimitiveID)); }
