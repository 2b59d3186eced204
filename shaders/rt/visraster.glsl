// Compute ("software") rasterization of the hybrid's visibility buffer (as Nanite does for small
// triangles): the same r32_uint ids as the hardware raster (rt/gbuffer.glsl vis_encode), formed
// as the camera rays of shaders/rt/shade.glsl see the scene.
//
// Coverage is the ray test itself, in camera-relative world space (homogeneous rasterization,
// Olano & Greer 1997): pixel p's ray direction D = forward + sx right + sy up (camera_ray before
// normalizing; sx, sy as there) lies in triangle (p0, p1, p2)'s cone iff the signed volumes
// dot(D, p1 x p2), dot(D, p2 x p0), dot(D, p0 x p1) all have the sign of h = dot(n, p0),
// n = (p1 - p0) x (p2 - p0); D is then a positive combination of the vertices, so the hit is in
// front of the camera. No near-plane clipping of the coverage: triangles crossing the camera
// plane or behind it are handled by the signs (the rays start at the camera, t > 0, like the
// stand-alone's). Depth: the ray meets the triangle's plane at z = h / dot(n, D) (D's forward
// part is 1), key = floatBitsToUint(1 / z) = floatBitsToUint(dot(n, D) / h): larger = nearer,
// float precision everywhere (like reversed Z), 0 = nothing.
//
// Edges are inclusive with a small relative epsilon: two triangles sharing an edge evaluate the
// same cross product with opposite signs (exact negation: edge_cross orders the edge by vertex
// index), so no pixel centre falls between them (no cracks). Over-coverage (a triangle claiming a pixel whose
// centre it just misses) is safe: the hybrid's shading passes trace the camera ray where the
// pixel centre misses the claimed triangle or the pixel borders another instance or the sky
// (shaders/rt/hybrid.glsl: first_hit), so such a pixel gets the stand-alone's answer.
//
// Two passes, 32-bit image atomics only: depth (atomicMax of the key) then id (where the key
// equals the stored one within KEY_ULPS, atomicMax of the id: ties between triangles resolve to
// the larger id, deterministic). Both evaluate the key with the same `precise` code.
// The screen bounding box only bounds the pixels tested (screen_box: the triangle clipped to the
// view frustum, near plane z >= forward.w, tiny: the coverage test decides).
#ifdef ATOMIC64
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#endif
#include "rt/tables.glsl"
#include "rt/gbuffer.glsl"

// Binding 5: depth keys, 6: visibility, 7: Args {job_count, 1, 1, overflow}, 8: jobs[] (triangle,
// tile y << 16 | x): declared by each shader with the access it makes.
layout(set = 0, binding = 4, std430) readonly buffer TriStart { uint tri_start[]; };  // per instance

layout(push_constant) uniform Raster {
    vec4 right;    // w: tan(fov_y / 2)
    vec4 up;       // w: aspect
    vec4 forward;  // w: z of the bounding-box clip plane
    uvec4 info;    // x: width, y: height, z: triangles (all instances), w: instances
} frame;

#ifndef TILE
#define TILE 32  // pixels per side of a tile job (a 16x16 workgroup, 2x2 pixels per thread)
#endif

struct Tri {
    vec3 c0, c1, c2;  // p1 x p2, p2 x p0, p0 x p1 (scaled by sign(h))
    vec3 n;           // plane normal / h: 1 / z = dot(n, D)
    vec3 eps;         // per-edge tolerance
    ivec4 box;        // inclusive pixel bounds x0 y0 x1 y1 (x1 < x0: nothing)
    uint id;
};

uint instance_of(uint t) {  // the largest i with tri_start[i] <= t
    uint lo = 0u, hi = frame.info.w - 1u;
    while (lo < hi) {
        uint mid = (lo + hi + 1u) >> 1;
        if (tri_start[mid] <= t) lo = mid; else hi = mid - 1u;
    }
    return lo;
}

float plane_side(int k, vec3 q, vec2 slope) {  // >= 0: inside plane k of the widened view frustum
    precise float f = k == 0 ? q.z - frame.forward.w : k == 1 ? slope.x * q.z - q.x : k == 2 ? slope.x * q.z + q.x
                    : k == 3 ? slope.y * q.z - q.y : slope.y * q.z + q.y;
    return f;
}

// The pixels whose centres the triangle may cover: the box of its part inside the view frustum
// (widened by a pixel; near plane z >= forward.w) projected, one more pixel of margin, clamped
// to the screen (Sutherland-Hodgman over 5 planes, at most 8 vertices; a triangle inside every
// plane skips it). Crossing or surrounding triangles thus get their on-screen box, not the whole
// screen. `precise`: every pass computes the same box (the big/small split and tile origins).
bool screen_box(vec3 p0, vec3 p1, vec3 p2, out ivec4 box) {
    box = ivec4(0, 0, -1, -1);
    precise vec2 slope = vec2(frame.right.w * frame.up.w * (1.0 + 2.0 / float(frame.info.x)),
                              frame.right.w * (1.0 + 2.0 / float(frame.info.y)));
    precise vec3 q[8];
    q[0] = vec3(dot(p0, frame.right.xyz), dot(p0, frame.up.xyz), dot(p0, frame.forward.xyz));
    q[1] = vec3(dot(p1, frame.right.xyz), dot(p1, frame.up.xyz), dot(p1, frame.forward.xyz));
    q[2] = vec3(dot(p2, frame.right.xyz), dot(p2, frame.up.xyz), dot(p2, frame.forward.xyz));
    int n = 3;
    for (int k = 0; k < 5; ++k) {
        bool all_in = true;
        for (int i = 0; i < n; ++i) all_in = all_in && plane_side(k, q[i], slope) >= 0.0;
        if (all_in) continue;
        precise vec3 r[8];
        int m = 0;
        for (int i = 0; i < n; ++i) {
            vec3 a = q[i], b = q[i + 1 < n ? i + 1 : 0];
            precise float fa = plane_side(k, a, slope), fb = plane_side(k, b, slope);
            if (fa >= 0.0 && m < 8) r[m++] = a;
            if ((fa >= 0.0) != (fb >= 0.0) && m < 8) r[m++] = a + (fa / (fa - fb)) * (b - a);
        }
        n = m;
        for (int i = 0; i < n; ++i) q[i] = r[i];
        if (n == 0) return false;  // wholly outside the view
    }
    precise vec4 b = vec4(1e30, 1e30, -1e30, -1e30);
    for (int i = 0; i < n; ++i) {
        precise vec2 sxy = q[i].xy / max(q[i].z, frame.forward.w);
        precise vec2 s = vec2((sxy.x / (frame.right.w * frame.up.w) + 1.0) * 0.5 * float(frame.info.x) - 0.5,
                              (1.0 - sxy.y / frame.right.w) * 0.5 * float(frame.info.y) - 0.5);
        b = vec4(min(b.xy, s), max(b.zw, s));
    }
    vec2 hi = vec2(frame.info.xy) - 1.0;
    b = vec4(clamp(floor(b.xy) - 1.0, vec2(-1.0), hi + 1.0), clamp(ceil(b.zw) + 1.0, vec2(-1.0), hi + 1.0));
    box = ivec4(max(b.xy, vec2(0.0)), min(b.zw, hi));
    return box.x <= box.z && box.y <= box.w;
}

// to_world of tables.glsl with `precise` (no contraction) inside: every pass and path must get
// bit-identical vertices, as the depth keys are compared for equality across compilations.
vec3 world_vertex(Instance I, uint v) {
    vec4 p = vec4(vertex_of(v), 1.0);
    precise vec3 w = vec3(dot(I.m0, p), dot(I.m1, p), dot(I.m2, p));
    return w;
}

// a x b for the edge from vertex ia to ib, always evaluated with the lower vertex index first:
// the two triangles sharing an edge then compute bit-identical products, and exact negations of
// them, whatever the compiler does inside cross. With cross(p1, p2) against cross(p2, p1), the
// H200 gave a far surface of the same mesh (a torus's back) on about 180 pixels of gallery camera
// 3 at 1280x720; lavapipe never did (docs/raytracing.md, session 9).
vec3 edge_cross(vec3 a, uint ia, vec3 b, uint ib) {
    precise vec3 c = ia < ib ? cross(a, b) : -cross(b, a);
    return c;
}

// Setup of global triangle t; false when it covers no pixel (degenerate, behind, off screen).
bool setup_triangle(uint t, out Tri tri) {
    uint instance = instance_of(t);
    uint prim = t - tri_start[instance];
    Instance I = inst[instance];
    uint base = I.info.x + 3u * prim;
    precise vec3 p0 = world_vertex(I, I.info.z + idx[base]);
    precise vec3 p1 = world_vertex(I, I.info.z + idx[base + 1u]);
    precise vec3 p2 = world_vertex(I, I.info.z + idx[base + 2u]);
    tri.id = vis_encode(instance, prim);
    tri.box = ivec4(0, 0, -1, -1);
    precise vec3 n = cross(p1 - p0, p2 - p0);
    precise float h = dot(n, p0);
    if (!(abs(h) > 0.0) || isinf(h)) return false;  // the plane passes through the camera (edge-on) or degenerate
    float s = h > 0.0 ? 1.0 : -1.0;
    uint i0 = idx[base], i1 = idx[base + 1u], i2 = idx[base + 2u];
    precise vec3 c0 = s * edge_cross(p1, i1, p2, i2), c1 = s * edge_cross(p2, i2, p0, i0), c2 = s * edge_cross(p0, i0, p1, i1);
    precise vec3 nh = n / h;
    precise vec3 eps = 1e-6 * vec3(length(c0), length(c1), length(c2));
    tri.c0 = c0; tri.c1 = c1; tri.c2 = c2; tri.n = nh; tri.eps = eps;
    return screen_box(p0, p1, p2, tri.box);
}

vec3 pixel_ray(ivec2 px) {  // camera_ray of shade.glsl before normalizing
    float sx = (2.0 * (float(px.x) + 0.5) / float(frame.info.x) - 1.0) * frame.right.w * frame.up.w;
    float sy = (1.0 - 2.0 * (float(px.y) + 0.5) / float(frame.info.y)) * frame.right.w;
    precise vec3 d = frame.forward.xyz + sx * frame.right.xyz + sy * frame.up.xyz;
    return d;
}

// Whether pixel px's centre ray hits the triangle (inclusive edges); its depth key.
bool cover(Tri tri, ivec2 px, out uint key) {
    precise vec3 d = pixel_ray(px);
    precise float e0 = dot(d, tri.c0), e1 = dot(d, tri.c1), e2 = dot(d, tri.c2);
    precise float w = dot(tri.n, d);
    key = floatBitsToUint(w);
    return e0 >= -tri.eps.x && e1 >= -tri.eps.y && e2 >= -tri.eps.z && w > 0.0 && !isinf(w);
}

// false only if no pixel centre of the rectangle lo..hi (inclusive) is covered: the edge values
// are affine in the pixel coordinates, so their maxima over it are at its corners.
bool rect_may_cover(Tri tri, ivec2 lo, ivec2 hi) {
    vec3 m = vec3(-1e38);
    for (int k = 0; k < 4; ++k) {
        vec3 d = pixel_ray(ivec2((k & 1) != 0 ? hi.x : lo.x, (k & 2) != 0 ? hi.y : lo.y));
        m = max(m, vec3(dot(d, tri.c0), dot(d, tri.c1), dot(d, tri.c2)));
    }
    return all(greaterThanEqual(m, -2.0 * tri.eps - 1e-6 * abs(m)));
}

// Whether tile t (TILE x TILE pixels counted from the triangle's box corner, clipped to the box)
// may hold a covered pixel centre (the tile jobs' test, rt/vistiles.comp).
bool tile_may_cover(Tri tri, ivec2 t) {
    ivec2 tile = tri.box.xy + t * TILE;
    return rect_may_cover(tri, tile, min(tile + (TILE - 1), tri.box.zw));
}

// The id pass's test against the stored (largest) key: equal within KEY_ULPS float ulps, so the
// nearest triangle keeps its pixel even if two compilations (depth / id pass, thread / tile path)
// round its key differently; a triangle that close in depth (a neighbour across a shared edge,
// coplanar z-fighting) may take the pixel instead (the larger id wins), which the shading passes'
// check of the pixel centre against the claimed triangle covers.
const uint KEY_ULPS = 2u;
bool key_matches(uint key, uint stored) { return key + KEY_ULPS >= stored && key <= stored + KEY_ULPS; }

// A big triangle's setup, stored once by the depth pass for its tile jobs (binding 10): both tile
// passes read the same record, so they rasterize with identical values and skip the setup.
struct TriRecord { vec4 c0, c1, c2, n; ivec4 box; };  // c*.w: eps, n.w: the id's bits
TriRecord pack_tri(Tri t) {
    return TriRecord(vec4(t.c0, t.eps.x), vec4(t.c1, t.eps.y), vec4(t.c2, t.eps.z), vec4(t.n, uintBitsToFloat(t.id)), t.box);
}
Tri unpack_tri(TriRecord r) {
    return Tri(r.c0.xyz, r.c1.xyz, r.c2.xyz, r.n.xyz, vec3(r.c0.w, r.c1.w, r.c2.w), r.box, floatBitsToUint(r.n.w));
}

uint pixels_of(Tri tri) { return uint(tri.box.z - tri.box.x + 1) * uint(tri.box.w - tri.box.y + 1); }

#ifdef ATOMIC64
// One 64-bit atomicMax per covered pixel: the nearest key wins, equal keys the larger id (the
// two-pass path's rule, without its cross-pass key tolerance: key and id come from one
// evaluation). The plain load skips most atomics: the stored value only grows, so a stale read
// can only under-estimate it.
layout(set = 0, binding = 15, std430) buffer VisKeys { uint64_t vis_keys[]; };
void visit64(ivec2 px, uint key, uint id) {
    uint i = uint(px.y) * frame.info.x + uint(px.x);
    uint64_t v = (uint64_t(key) << 32) | uint64_t(id);
    if (vis_keys[i] < v) atomicMax(vis_keys[i], v);
}
#endif
