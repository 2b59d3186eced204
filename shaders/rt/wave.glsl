// The hybrid's wavefront ray tree (graphs/rt_hybrid.yaml; passes/raytrace_wave.py): the nodes of
// tree level k are the records of list k, traced by one launch per level (hybrid_wave.rgen); each
// node's radiance goes to its pixel's accumulator, its children to list k + 1.
//
// Accumulation is deterministic: 64-bit fixed point (2^-32 units; every contribution is >= 0)
// added with integer atomics, so the sum does not depend on the order in which rays run or
// were appended. Nothing is dropped: a child that does not fit list k + 1 (RAY_CAPACITY), or any
// child at the last level that has a list (no NEXT_LIST), is walked in-thread by the existing
// stack walk (shade.glsl: walk) and added with its parent's radiance.
// Needs common.glsl and shade.glsl (stack, push_children, walk) included before; bindings:
// 12 = the accumulators (3 uint64 per listed pixel), NEXT_LIST: 13 = list k + 1, 14 = its
// indirect arguments (count, 1, 1, overflow flag). SUBGROUP_APPEND (rt.wave_subgroup, where the
// device has subgroup operations in ray generation shaders) reserves list slots with one atomic
// per subgroup instead of one per invocation; the slots stay contiguous either way.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#ifdef SUBGROUP_APPEND
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
// One atomic per subgroup: the active invocations' n summed, their slots by an exclusive scan.
#define APPEND(counter, n, first) { uint total_ = subgroupAdd(n); uint base_ = 0u; \
    if (subgroupElect()) base_ = atomicAdd(counter, total_); \
    first = subgroupBroadcastFirst(base_) + subgroupExclusiveAdd(n); }
#else
#define APPEND(counter, n, first) { first = atomicAdd(counter, n); }
#endif

layout(set = 0, binding = 12, std430) buffer Accum { uint64_t acc[]; };

const float FIXED_ONE = 4294967296.0;  // 2^32
const float FIXED_MAX = 1073741824.0;  // 2^30 per contribution: no overflow of 64 bits

uint64_t to_fixed(float c) {
    return uint64_t(c > 0.0 ? min(c, FIXED_MAX) * FIXED_ONE : 0.0);  // NaN -> 0
}

// Ray records: (origin, owner slot bits), (direction, weight r), (weight g, b, path, -).
struct RayRecord { vec4 a; vec4 b; vec4 c; };

#ifdef NEXT_LIST
layout(set = 0, binding = 13, std430) writeonly buffer NextRays { RayRecord next_rays[]; };
layout(set = 0, binding = 14, std430) buffer NextArgs { uint next_count; uint next_h; uint next_d; uint next_overflow; };
#endif

// The children on the stack (push_children) go to the next list when they fit (one reservation
// for all of them; a reservation past RAY_CAPACITY is undone, so the list stays contiguous and
// its count within the capacity); whatever stays on the stack is walked here. Returns the
// radiance walked in-thread. LIST_FITS: the list has room for every parent's children (two per
// parent slot), so there is no fallback walk to compile.
vec3 spill_and_walk(uint owner) {
#ifdef NEXT_LIST
    if (top > 0u) {
        uint n = top;
        uint first;
        APPEND(next_count, n, first);
#ifdef LIST_FITS
        if (true) {
#else
        if (first + n <= RAY_CAPACITY) {
#endif
            for (uint i = 0u; i < n; ++i) {
                Ray r = stack[i];
                next_rays[first + i] = RayRecord(vec4(r.o, uintBitsToFloat(owner)), vec4(r.d, r.w.x), vec4(r.w.yz, r.path, 0.0));
            }
            top = 0u;
        } else {
            atomicAdd(next_count, 0u - n);
            next_overflow = 1u;
        }
    }
#endif
#ifdef LIST_FITS
    return vec3(0.0);
#else
    return walk();
#endif
}
