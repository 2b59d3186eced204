#version 460
#extension GL_GOOGLE_include_directive : require
// light_assign: one workgroup per froxel. Lights whose sphere meets the froxel's AABB (spot lights
// also: whose cone meets the AABB's bounding sphere; directional lights: always) go to a compact
// list: light_grid = (offset, count) into light_indices, indices ascending. Two sweeps over the
// lights: count, reserve (atomicAdd), write. A list that does not fit the buffer is not written:
// its froxel gets count CLUSTER_OVERFLOW (forward then shades every light there) and the
// statistics count it (stats: 0 light references asked for, 1 overflowed froxels, 2 longest list,
// 3 capacity in indices).
#include "scene/scene.glsl"
#include "clustered/clusters.glsl"

#define GROUP 64
layout(local_size_x = GROUP) in;
layout(set = 1, binding = 0, std430) readonly buffer Lights { Light lights[]; };
layout(set = 1, binding = 1, rgba32f) uniform readonly image2DArray froxel_bounds;
layout(set = 1, binding = 2, rgba32ui) uniform writeonly uimage2DArray light_grid;
layout(set = 1, binding = 3, std430) writeonly buffer Indices { uint indices[]; };
layout(set = 1, binding = 4, std430) buffer Stats { uint stats[4]; };
layout(push_constant) uniform Push { uint capacity; uint light_count; } pc;

shared uint s_mask[2];
shared uint s_offset;
shared uint s_state;  // 0 ok, 1 overflow

bool touches(uint i, vec3 lo, vec3 hi) {
    Light light = lights[i];
    int type = int(light.to_light.w + 0.5);
    if (type == LIGHT_DIRECTIONAL) return true;
    vec3 c = light.view.xyz;
    float r = max(light.position.w, LIGHT_MIN_RADIUS) * (1.0 + CLUSTER_PAD);
    vec3 q = clamp(c, lo, hi) - c;
    if (dot(q, q) > r * r) return false;
    if (type == LIGHT_SPOT) {
        float sr = 0.5 * length(hi - lo);
        if (sr > 1e15) return true;  // the unbounded last slice: keep it (conservative)
        vec3 axis = -(mat3(frame.view) * light.to_light.xyz);  // the direction the spot shines (view space)
        float cos_o = scene_lights[i].radiance.w;
        float sin_o = sqrt(max(1.0 - cos_o * cos_o, 0.0));
        vec3 v = 0.5 * (lo + hi) - c;
        float v1 = dot(v, axis);
        float closest = cos_o * sqrt(max(dot(v, v) - v1 * v1, 0.0)) - v1 * sin_o;
        sr *= 1.0 + CLUSTER_PAD;
        if (closest > sr || v1 < -sr) return false;
    }
    return true;
}


// One sweep: count (write = false) or write the list from s_offset.
uint sweep(bool write, vec3 lo, vec3 hi, uint n) {
    uint tid = gl_LocalInvocationID.x;
    uint total = 0u;
    for (uint base = 0u; base < n; base += GROUP) {
        if (tid < 2u) s_mask[tid] = 0u;
        barrier();
        uint i = base + tid;
        bool hit = i < n && touches(i, lo, hi);
        if (hit) atomicOr(s_mask[tid >> 5], 1u << (tid & 31u));
        barrier();
        uint m0 = s_mask[0], m1 = s_mask[1];
        if (write && hit) {
            uint below = tid < 32u ? bitCount(m0 & ((1u << tid) - 1u))
                                   : bitCount(m0) + bitCount(m1 & ((1u << (tid - 32u)) - 1u));
            indices[s_offset + total + below] = i;
        }
        total += uint(bitCount(m0) + bitCount(m1));
        barrier();
    }
    return total;
}

#if LIST_BITMASK
// LIST_BITMASK: the froxel's list is a bitmask of ceil(n / 32) words at froxel_index * words
// (light i = bit i % 32 of word i / 32); light_grid = (offset, lights set). One sweep, no atomics
// for the offset; the froxels past the capacity overflow.
void bitmask_main(ivec3 c, vec3 lo, vec3 hi, uint n) {
    uint tid = gl_LocalInvocationID.x;
    uint words = (n + 31u) / 32u;
    uint froxel = uint((c.z * GRID_Y + c.y) * GRID_X + c.x);
    bool over = words > 0u && (froxel >= pc.capacity / words);
    uint offset = froxel * words;
    uint total = 0u;
    for (uint base = 0u; base < n; base += GROUP) {
        if (tid < 2u) s_mask[tid] = 0u;
        barrier();
        uint i = base + tid;
        bool hit = i < n && touches(i, lo, hi);
        if (hit) atomicOr(s_mask[tid >> 5], 1u << (tid & 31u));
        barrier();
        uint w = base / 32u + tid;
        if (!over && tid < 2u && w < words) indices[offset + w] = s_mask[tid];
        total += uint(bitCount(s_mask[0]) + bitCount(s_mask[1]));
        barrier();
    }
    if (tid == 0u) {
        atomicAdd(stats[0], words);
        atomicMax(stats[2], total);
        if (c == ivec3(0)) stats[3] = pc.capacity;
        if (over) atomicAdd(stats[1], 1u);
        imageStore(light_grid, c, uvec4(over ? 0u : offset, over ? CLUSTER_OVERFLOW : total, 0u, 0u));
    }
}
#endif

void main() {
    ivec3 c = ivec3(gl_WorkGroupID);
    uint tid = gl_LocalInvocationID.x;
    vec3 lo = imageLoad(froxel_bounds, ivec3(c.xy, 2 * c.z)).xyz;
    vec3 hi = imageLoad(froxel_bounds, ivec3(c.xy, 2 * c.z + 1)).xyz;
    uint n = pc.light_count;
#if LIST_BITMASK
    bitmask_main(c, lo, hi, n);
    return;
#endif
    uint count = sweep(false, lo, hi, n);
    if (tid == 0u) {
        uint offset = atomicAdd(stats[0], count);
        atomicMax(stats[2], count);
        if (c == ivec3(0)) stats[3] = pc.capacity;
        bool over = count > pc.capacity || offset > pc.capacity - count;
        if (over) atomicAdd(stats[1], 1u);
        s_offset = offset;
        s_state = over ? 1u : 0u;
        imageStore(light_grid, c, uvec4(over ? 0u : offset, over ? CLUSTER_OVERFLOW : count, 0u, 0u));
    }
    barrier();
    if (s_state == 0u && count > 0u) sweep(true, lo, hi, n);
}
