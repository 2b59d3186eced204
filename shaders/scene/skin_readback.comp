#version 460
#extension GL_GOOGLE_include_directive : require
// skin_readback (passes/skin_readback.py): the posed positions and normals of one skinned mesh,
// every instance, through the same scene/skinning.glsl as the vertex shaders - read back by
// tests and compared with the NumPy reference. out[instance * vertices + v] = (position, 1),
// then the normals after all positions.
#include "scene/scene.glsl"

layout(local_size_x = 64) in;
layout(push_constant) uniform Push {
    uint first_vertex;   // the mesh's first vertex in the rigid vertex buffer (= SkinVertices index)
    uint vertices;
    uint first_draw;
    uint instances;
    float alpha;         // < 0: the frame's SkinFrame.alpha
} pc;
#define SKIN_ALPHA (pc.alpha >= 0.0 ? pc.alpha : skin_frame.alpha)
#include "scene/skinning.glsl"

layout(set = 1, binding = 0, std430) writeonly buffer Out { vec4 posed[]; };
layout(set = 1, binding = 1, std430) readonly buffer Rest { float rest[]; };  // the mesh's rest vertices (pos, normal)

void main() {
    uint v = gl_GlobalInvocationID.x, c = gl_GlobalInvocationID.y;
    if (v >= pc.vertices || c >= pc.instances) return;
    vec3 p = vec3(rest[6u * v], rest[6u * v + 1u], rest[6u * v + 2u]);
    vec3 n = vec3(rest[6u * v + 3u], rest[6u * v + 4u], rest[6u * v + 5u]);
    skin_vertex(pc.first_vertex + v, pc.first_draw + c, p, n);
    posed[c * pc.vertices + v] = vec4(p, 1.0);
    posed[(pc.instances + c) * pc.vertices + v] = vec4(n, 0.0);
}
