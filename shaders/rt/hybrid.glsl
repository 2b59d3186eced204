// The hybrid's view of the visibility buffer (set 0 binding 8): the first surface of pixel px,
// reconstructed from instance + primitive: the camera ray (origin 0, direction d) intersected
// with that triangle (Moller-Trumbore, camera-relative world space), so the hit point, the
// barycentrics and both normals are formed as the stand-alone's closest hit forms them
// (common.glsl: surface). No depth is read: depth reconstruction is too coarse for shadow-ray
// offsets at grazing angles.
#include "rt/gbuffer.glsl"
layout(set = 0, binding = 8) uniform usampler2D visibility;

// false: nothing (the sky).
bool first_hit(uvec2 px, vec3 d, out Hit h) {
    uint id = texelFetch(visibility, ivec2(px), 0).r;
    if (id == 0u) return false;
    h.instance = vis_instance(id);
    h.prim = vis_prim(id);
    Instance I = inst[h.instance];
    uint base = I.info.x + 3u * h.prim;
    vec3 p0 = to_world(I, vertex_of(I.info.z + idx[base]));
    vec3 p1 = to_world(I, vertex_of(I.info.z + idx[base + 1u]));
    vec3 p2 = to_world(I, vertex_of(I.info.z + idx[base + 2u]));
    vec3 e1 = p1 - p0, e2 = p2 - p0, q = cross(d, e2);
    float det = dot(e1, q);
    float inv = abs(det) > 1e-30 ? 1.0 / det : 0.0;
    vec3 s = -p0;  // ray origin 0 - p0
    vec3 r = cross(s, e1);
    // clamp: the raster covered this pixel centre, the ray may graze just outside the edge
    float u = clamp(dot(s, q) * inv, 0.0, 1.0), v = clamp(dot(d, r) * inv, 0.0, 1.0 - u);
    h.bary = vec2(u, v);
    h.t = max(dot(e2, r) * inv, 0.0);
    return true;
}
