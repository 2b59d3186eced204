// The hybrid's view of the visibility buffer (set 0 binding 8): the first surface of pixel px,
// reconstructed from instance + primitive: the camera ray (origin 0, direction d) intersected
// with that triangle (Moller-Trumbore, camera-relative world space), so the hit point, the
// barycentrics and both normals are formed as the stand-alone's closest hit forms them
// (common.glsl: surface). No depth is read. Where raster and ray may disagree (the pixel borders
// another instance or the sky, or the pixel centre misses the rasterized triangle: snapped
// vertices, edge rules) the camera ray is traced instead, as the stand-alone does.
// Needs shade.glsl (trace_closest) included before; with NO_TRACE only raster_hit.
#include "rt/gbuffer.glsl"
layout(set = 0, binding = 8) uniform usampler2D visibility;

uint instance_at(ivec2 p) {
    uint id = texelFetch(visibility, clamp(p, ivec2(0), ivec2(frame.counts.xy) - 1), 0).r;
    return id == 0u ? 0xFFFFFFFFu : vis_instance(id);
}

bool on_boundary(ivec2 p, uint inst) {
    return instance_at(p + ivec2(1, 0)) != inst || instance_at(p - ivec2(1, 0)) != inst
        || instance_at(p + ivec2(0, 1)) != inst || instance_at(p - ivec2(0, 1)) != inst;
}

// The camera ray's hit on triangle (instance, prim); false when the ray misses it.
bool hit_triangle(vec3 d, uint instance, uint prim, out Hit h) {
    Instance I = inst[instance];
    uint base = I.info.x + 3u * prim;
    vec3 p0 = to_world(I, vertex_of(I.info.z + idx[base]));
    vec3 p1 = to_world(I, vertex_of(I.info.z + idx[base + 1u]));
    vec3 p2 = to_world(I, vertex_of(I.info.z + idx[base + 2u]));
    vec3 e1 = p1 - p0, e2 = p2 - p0, q = cross(d, e2);
    float det = dot(e1, q);
    if (abs(det) < 1e-30) return false;
    float inv = 1.0 / det;
    vec3 s = -p0;  // ray origin 0 - p0
    vec3 r = cross(s, e1);
    float u = dot(s, q) * inv, v = dot(d, r) * inv, t = dot(e2, r) * inv;
    h = Hit(t, instance, prim, vec2(u, v));
    return u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0;
}

// Whether the secondary pass shades pixel px (its visible instance's material reflects or
// refracts: the test of classify.comp, which put px on the compacted list).
bool classified(uvec2 px) {
    uint id = texelFetch(visibility, ivec2(px), 0).r;
    if (id == 0u) return false;
    vec4 k = mat[2u * inst[vis_instance(id)].info.y + 1u];
    return k.x > 0.0 || k.y > 0.0;
}

// The first surface from the visibility buffer alone: 1 the rasterized triangle's hit (h), 0 the
// sky, -1 raster and ray may disagree (the camera ray must be traced).
int raster_hit(uvec2 px, vec3 d, out Hit h) {
    uint id = texelFetch(visibility, ivec2(px), 0).r;
    uint instance = id == 0u ? 0xFFFFFFFFu : vis_instance(id);
    bool boundary = on_boundary(ivec2(px), instance);
    if (id == 0u && !boundary) return 0;
    if (id != 0u && !boundary && hit_triangle(d, instance, vis_prim(id), h)) return 1;
    return -1;
}

#ifndef NO_TRACE
// false: nothing (the sky).
bool first_hit(uvec2 px, vec3 d, out Hit h) {
    int raster = raster_hit(px, d, h);
    if (raster >= 0) return raster == 1;
    h = trace_closest(vec3(0.0), d);
    return h.t >= 0.0;
}
#endif
