#version 460
// deform_normals: the deformable meshes' vertices of one frame (rgraph.vk.scene_deform).
// One invocation per vertex v: its position (the two logic states mixed by alpha), its
// smoothed normal (a fixed-order gather over its smoothing group's CSR triangle list: no
// atomics, reproducible) and its tangent. The rule, and the float64 reference it is tested
// against: rgraph/scene/smoothing.py. With NORMALS_ONLY (the ray tracing tables,
// rgraph/vk/rt_deform.py): the ring is one slot of positions, binding 8 takes the normals alone
// (3 floats per vertex), no UVs, no tangents.

layout(local_size_x = 64) in;

// host-written: per frame set which two ring slots to mix (alpha 1: exactly the current one)
layout(set = 0, binding = 0, std430) readonly buffer Header { float alpha; uint prev_slot; uint cur_slot; };
layout(set = 0, binding = 1, std430) readonly buffer Ring { float ring_pos[]; };  // slots of pc.total vertices
layout(set = 0, binding = 2, std430) readonly buffer Groups { uint group_of[]; };
layout(set = 0, binding = 3, std430) readonly buffer Offsets { uint offsets[]; };
layout(set = 0, binding = 4, std430) readonly buffer Triangles { uint triangles[]; };
layout(set = 0, binding = 5, std430) readonly buffer Indices { uint indices[]; };  // 3 per triangle
#ifndef NORMALS_ONLY
layout(set = 0, binding = 6, std430) readonly buffer Uvs { vec2 uvs[]; };
#endif
layout(set = 0, binding = 7, std430) readonly buffer Fallback { float fallback[]; };  // rest normals
#ifdef NORMALS_ONLY
layout(set = 0, binding = 8, std430) writeonly buffer Normals { float normals_out[]; };  // normal
#else
layout(set = 0, binding = 8, std430) writeonly buffer Vertices { float vertices[]; };  // position, normal
layout(set = 0, binding = 9, std430) writeonly buffer Tangents { vec4 tangents[]; };
#endif

layout(push_constant) uniform Push {
    uint first;  // the mesh's first vertex
    uint count;  // its vertices
    uint total;  // deformable vertices of the scene (a ring slot's size)
    float scale; // a power of two: positions * scale are about unit size
} pc;

const float REL = 1e-5;

vec3 position(uint v) {
    uint o0 = 3u * (prev_slot * pc.total + v);
    uint o1 = 3u * (cur_slot * pc.total + v);
    precise vec3 p0 = vec3(ring_pos[o0], ring_pos[o0 + 1u], ring_pos[o0 + 2u]);
    precise vec3 p1 = vec3(ring_pos[o1], ring_pos[o1 + 1u], ring_pos[o1 + 2u]);
    precise vec3 p = p0 * (1.0 - alpha) + p1 * alpha;  // alpha 1: exactly p1
    return p;
}

// a * b - c * d with the rounding error of c * d recovered (Kahan): exact zero for parallel edges
float dop(float a, float b, float c, float d) {
    precise float w = c * d;
    precise float e = fma(-c, d, w);
    precise float f = fma(a, b, -w);
    precise float r = f + e;
    return r;
}

vec3 cross_accurate(vec3 x, vec3 y) {
    return vec3(dop(x.y, y.z, x.z, y.y), dop(x.z, y.x, x.x, y.z), dop(x.x, y.y, x.y, y.x));
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    uint v = pc.first + i;
    uint g = group_of[v];
    vec3 acc = vec3(0.0);
    float total = 0.0;
    vec3 big_t = vec3(0.0);
    vec3 big_b = vec3(0.0);
    for (uint k = offsets[g]; k < offsets[g + 1u]; ++k) {
        uint t = triangles[k];
        uint i0 = indices[3u * t], i1 = indices[3u * t + 1u], i2 = indices[3u * t + 2u];
        vec3 p0 = position(i0) * pc.scale;
        vec3 e1 = position(i1) * pc.scale - p0;
        vec3 e2 = position(i2) * pc.scale - p0;
        vec3 f = cross_accurate(e1, e2);
        acc += f;
        total += length(f);
#ifndef NORMALS_ONLY
        if (i0 == v || i1 == v || i2 == v) {  // the vertex's own triangles (its UV chart): tangents
            vec2 d1 = uvs[i1] - uvs[i0];
            vec2 d2 = uvs[i2] - uvs[i0];
            float s = sign(dop(d1.x, d2.y, d2.x, d1.y));
            big_t += (e1 * d2.y - e2 * d1.y) * s;
            big_b += (e2 * d1.x - e1 * d2.x) * s;
        }
#endif
    }
    float len = length(acc);
    vec3 n = (total > 0.0 && len > REL * total)
        ? acc / len : vec3(fallback[3u * v], fallback[3u * v + 1u], fallback[3u * v + 2u]);
#ifdef NORMALS_ONLY
    normals_out[3u * v] = n.x;
    normals_out[3u * v + 1u] = n.y;
    normals_out[3u * v + 2u] = n.z;
#else
    vec3 t = big_t - n * dot(n, big_t);
    float t_len = length(t);
    float big_len = length(big_t);
    if (big_len > 0.0 && t_len > REL * big_len) {
        t /= t_len;
    } else {
        vec3 axis = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
        t = normalize(axis - n * dot(n, axis));
    }
    float w = dot(cross(n, t), big_b) < 0.0 ? -1.0 : 1.0;
    vec3 p = position(v);
    vertices[6u * v] = p.x;
    vertices[6u * v + 1u] = p.y;
    vertices[6u * v + 2u] = p.z;
    vertices[6u * v + 3u] = n.x;
    vertices[6u * v + 4u] = n.y;
    vertices[6u * v + 5u] = n.z;
    tangents[v] = vec4(t, w);
#endif
}
