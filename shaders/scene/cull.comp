#version 460
#extension GL_GOOGLE_include_directive : require
// GPU frustum culling (draw.mode=gpu): one thread per instance tests its bounding sphere
// against every view's frustum (reversed-Z, infinite far: 5 planes from view_proj's rows) and
// appends a VkDrawIndexedIndirectCommand (instanceCount 1, firstInstance = the instance id)
// for each visible one; the count at offset 0 feeds vkCmdDrawIndexedIndirectCount.
// RESET=1: the one-thread variant that zeroes the count (draw_reset, before draw_cull).
// NumPy reference: rgraph/scene/instances.py visible().
#include "scene/scene.glsl"

layout(local_size_x = 64) in;

struct DrawCommand {
    uint index_count;
    uint instance_count;
    uint first_index;
    int vertex_offset;
    uint first_instance;
};

// the graph buffer draw_args: count, 3 words of padding, then the commands
layout(set = 1, binding = 0, std430) buffer DrawArgs {
    uint draw_count;
    uint pad0, pad1, pad2;
    DrawCommand commands[];
};

layout(push_constant) uniform Push { uint instance_count; uint capacity; } pc;

bool sphere_in_frustum(vec3 c, float r, mat4 m) {
    // rows of m (GLSL matrices are column-major: m[col][row])
    vec4 x = vec4(m[0][0], m[1][0], m[2][0], m[3][0]);
    vec4 y = vec4(m[0][1], m[1][1], m[2][1], m[3][1]);
    vec4 z = vec4(m[0][2], m[1][2], m[2][2], m[3][2]);
    vec4 w = vec4(m[0][3], m[1][3], m[2][3], m[3][3]);
    vec4 planes[5] = vec4[5](w + x, w - x, w + y, w - y, w - z);
    for (int k = 0; k < 5; ++k) {
        if (dot(planes[k].xyz, c) + planes[k].w < -r * length(planes[k].xyz)) return false;
    }
    return true;
}

void main() {
#if RESET
    if (gl_GlobalInvocationID.x == 0u) draw_count = 0u;
#else
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.instance_count) return;
    uvec4 info = instances[i].info;
    if ((info.z & 1u) != 0u) return;  // deformable meshes are drawn directly
    vec3 c = scene_translation(i) + instances[i].sphere.xyz;
    float r = instances[i].sphere.w;
    bool keep = false;
    for (uint v = 0u; v < uint(RGRAPH_VIEWS); ++v) keep = keep || sphere_in_frustum(c, r, scene_view_proj(v));
    if (!keep) return;
    uint slot = atomicAdd(draw_count, 1u);
    if (slot >= pc.capacity) return;
    uvec4 mesh = meshes[info.y];
    commands[slot] = DrawCommand(mesh.x, 1u, mesh.y, int(mesh.z), i);
#endif
}
