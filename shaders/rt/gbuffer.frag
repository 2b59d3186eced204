#version 460
#extension GL_GOOGLE_include_directive : require
#include "rt/gbuffer.glsl"
layout(location = 0) in vec3 v_normal;
layout(location = 1) flat in uint v_material;
layout(location = 0) out vec2 o_normal;
layout(location = 1) out uint o_material;

void main() {
    vec3 n = normalize(v_normal);
    o_normal = oct_encode(n);
    o_material = v_material + 1u;
}
