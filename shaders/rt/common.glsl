// Shared by the ray tracing passes: scene tables, sky cube map lookup, Wächter-Binder ray
// offsets, the lighting model (passes/rt_model.py and its NumPy reference passes/rt_ref.py).
#ifndef NO_TRACE  // NO_TRACE: a compute pass (hybrid_first.comp) that shades without tracing
#extension GL_EXT_ray_tracing : require
#endif

#include "rt/tables.glsl"
layout(set = 0, binding = 2, std430) readonly buffer Normals { float nrm[]; };
layout(set = 0, binding = 4, std430) readonly buffer Materials { vec4 mat[]; };  // albedo.rgb ks | kr kt ior n
layout(set = 0, binding = 5, std430) readonly buffer Lights { vec4 lights[]; };  // xyz type | radiance
layout(set = 0, binding = 6) uniform sampler2DArray sky_map;
#ifndef NO_TRACE
layout(set = 1, binding = 0) uniform accelerationStructureEXT tlas;
#endif

layout(push_constant) uniform Frame {
    vec4 right;     // w: tan(fov_y / 2)
    vec4 up;        // w: aspect
    vec4 forward;
    uvec4 counts;   // x: width, y: height, z: max depth, w: lights
} frame;

struct Hit { float t; uint instance; uint prim; vec2 bary; };

const vec3 AMBIENT = vec3(0.03, 0.03, 0.035);
const float T_MAX = 1e30;

vec3 offset_ray(vec3 p, vec3 n) {  // Ray Tracing Gems ch. 6
    const float origin = 1.0 / 32.0, float_scale = 1.0 / 65536.0, int_scale = 256.0;
    ivec3 of_i = ivec3(int_scale * n);
    vec3 p_i = vec3(intBitsToFloat(floatBitsToInt(p.x) + (p.x < 0.0 ? -of_i.x : of_i.x)),
                    intBitsToFloat(floatBitsToInt(p.y) + (p.y < 0.0 ? -of_i.y : of_i.y)),
                    intBitsToFloat(floatBitsToInt(p.z) + (p.z < 0.0 ? -of_i.z : of_i.z)));
    return vec3(abs(p.x) < origin ? p.x + float_scale * n.x : p_i.x,
                abs(p.y) < origin ? p.y + float_scale * n.y : p_i.y,
                abs(p.z) < origin ? p.z + float_scale * n.z : p_i.z);
}

vec3 safe_normalize(vec3 v, vec3 fallback) {
    float n = length(v);
    return (n > 1e-20 && !isinf(n)) ? v / n : fallback;
}

vec3 sample_sky(vec3 d) {
    vec3 a = abs(d);
    uint face; float sc, tc, ma;
    if (a.x >= a.y && a.x >= a.z) { ma = a.x; if (d.x >= 0.0) { face = 0u; sc = -d.z; tc = -d.y; } else { face = 1u; sc = d.z; tc = -d.y; } }
    else if (a.y >= a.z) { ma = a.y; if (d.y >= 0.0) { face = 2u; sc = d.x; tc = d.z; } else { face = 3u; sc = d.x; tc = -d.z; } }
    else { ma = a.z; if (d.z >= 0.0) { face = 4u; sc = d.x; tc = -d.y; } else { face = 5u; sc = -d.x; tc = -d.y; } }
    ma = max(ma, 1e-30);
    int size = textureSize(sky_map, 0).x;
    int i = min(int(0.5 * (sc / ma + 1.0) * float(size)), size - 1);
    int j = min(int(0.5 * (tc / ma + 1.0) * float(size)), size - 1);
    return texelFetch(sky_map, ivec3(max(i, 0), max(j, 0), int(face)), 0).rgb;
}

vec3 normal_of(uint v) { return vec3(nrm[3u * v], nrm[3u * v + 1u], nrm[3u * v + 2u]); }
vec3 normal_to_world(Instance I, vec3 n) { return vec3(dot(I.n0.xyz, n), dot(I.n1.xyz, n), dot(I.n2.xyz, n)); }

// Geometric and shading normals (world), oriented alike.
void surface(Hit h, vec3 d, out vec3 ng, out vec3 ns, out uint material) {
    Instance I = inst[h.instance];
    uint base = I.info.x + 3u * h.prim;
    uint a = I.info.z + idx[base], b = I.info.z + idx[base + 1u], c = I.info.z + idx[base + 2u];
    vec3 p0 = to_world(I, vertex_of(a)), p1 = to_world(I, vertex_of(b)), p2 = to_world(I, vertex_of(c));
    ng = safe_normalize(cross(p1 - p0, p2 - p0), -d);
    vec3 n = (1.0 - h.bary.x - h.bary.y) * normal_of(a) + h.bary.x * normal_of(b) + h.bary.y * normal_of(c);
    ns = safe_normalize(normal_to_world(I, n), ng);
    if (dot(ng, ns) < 0.0) ng = -ng;
    material = I.info.y;
}
