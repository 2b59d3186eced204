#version 460
#extension GL_GOOGLE_include_directive : require
// GPU frustum culling (draw.mode=gpu): one thread per instance tests its bounding sphere
// against every view's frustum (reversed-Z, infinite far: 5 planes from view_proj's rows) and
// emits a VkDrawIndexedIndirectCommand (instanceCount 1, firstInstance = the instance id)
// for each visible one; the count at offset 0 feeds vkCmdDrawIndexedIndirectCount.
// RESET=1: the variant that zeroes the count, the order's counters (draw_reset, before draw_cull).
// ORDERED=0 (draw.order=none): each visible instance appends its command (atomic order).
// ORDERED=1 (draw.order=front_to_back): each visible instance counts itself into one of
// BUCKETS distance buckets (log-spaced from the near plane to the far side of the scene bounds,
// by the nearest point of its sphere) and notes (bucket, rank); the last workgroup to finish
// scans the bucket counts and writes every command at its bucket's offset + rank, so the
// commands run near to far (in atomic order within a bucket): early depth rejection for the
// raster passes. Layout of draw_args in 32-bit words: count, groups done, 2 pad, then
// commands[capacity] (5 words each), bucket counts[BUCKETS], bucket_of[capacity], rank_of[capacity].
// NumPy reference: rgraph/scene/instances.py visible() and draw_buckets().
#include "scene/scene.glsl"

#ifndef ORDERED
#define ORDERED 0
#endif
#define BUCKETS 256u
#define GROUP 256u
#define CULLED 0xFFFFFFFFu

layout(local_size_x = 256) in;

layout(set = 1, binding = 0, std430) coherent buffer DrawArgs {
    uint draw_count;
    uint groups_done;
    uint pad0, pad1;
    uint words[];
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

void write_command(uint slot, uint i) {
    uvec4 mesh = meshes[instances[i].info.y];
    uint base = 5u * slot;
    words[base] = mesh.x;
    words[base + 1u] = 1u;
    words[base + 2u] = mesh.y;
    words[base + 3u] = mesh.z;  // vertexOffset (int32 bits)
    words[base + 4u] = i;
}

// Distance bucket of a sphere (camera-relative centre c, radius r): log-spaced over
// [near, far side of the scene bounds], the nearest point of the sphere.
uint bucket_of_sphere(vec3 c, float r) {
    float near_plane = max(frame.time.z, 1e-6);
    float far_side = max(length(frame.scene_bounds.xyz) + frame.scene_bounds.w, near_plane * 2.0);
    float d = max(length(c) - r, near_plane);
    float u = log(d / near_plane) / log(far_side / near_plane);
    return min(uint(max(u, 0.0) * float(BUCKETS)), BUCKETS - 1u);
}

#if ORDERED
shared bool last_group;
shared uint offsets[BUCKETS];
#endif

void main() {
    uint t = gl_LocalInvocationIndex;
#if RESET
    if (t == 0u) { draw_count = 0u; groups_done = 0u; }
#if ORDERED
    if (t < BUCKETS) words[5u * pc.capacity + t] = 0u;
#endif
#else
    // groups fold into rows (rgraph/vk/dispatch.py): more than 65,535 groups of instances
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * GROUP + t;
    bool keep = false;
    vec3 c = vec3(0.0);
    float r = 0.0;
    if (i < pc.instance_count && (instances[i].info.z & 1u) == 0u) {  // deformable meshes are drawn directly
        c = scene_translation(i) + instances[i].sphere.xyz;
        r = instances[i].sphere.w;
        for (uint v = 0u; v < uint(RGRAPH_VIEWS); ++v) keep = keep || sphere_in_frustum(c, r, scene_view_proj(v));
    }
#if !ORDERED
    if (keep) {
        uint slot = atomicAdd(draw_count, 1u);
        if (slot < pc.capacity) write_command(slot, i);
    }
#else
    uint counts = 5u * pc.capacity, bucket_at = counts + BUCKETS, rank_at = bucket_at + pc.capacity;
    if (i < pc.instance_count) {
        uint b = CULLED;
        if (keep) {
            b = bucket_of_sphere(c, r);
            words[rank_at + i] = atomicAdd(words[counts + b], 1u);
        }
        words[bucket_at + i] = b;
    }
    // The last workgroup to get here sees every other group's notes (their writes made
    // available before their groups_done increment; coherent buffer).
    memoryBarrierBuffer();
    barrier();
    if (t == 0u) last_group = atomicAdd(groups_done, 1u) == gl_NumWorkGroups.x * gl_NumWorkGroups.y - 1u;
    barrier();
    if (last_group) {
        memoryBarrierBuffer();
        offsets[t] = atomicAdd(words[counts + t], 0u);  // GROUP == BUCKETS: a count per thread
        barrier();
        if (t == 0u) {
            uint total = 0u;
            for (uint k = 0u; k < BUCKETS; ++k) { uint n = offsets[k]; offsets[k] = total; total += n; }
            draw_count = total;
        }
        barrier();
        for (uint j = t; j < pc.instance_count; j += GROUP) {
            uint b = words[bucket_at + j];
            if (b != CULLED) write_command(offsets[b] + words[rank_at + j], j);
        }
    }
#endif
#endif
}
