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
// same cross product with opposite signs (exact negation; `precise` forbids contraction), so no
// pixel centre falls between them (no cracks). Over-coverage (a triangle claiming a pixel whose
// centre it just misses) is safe: the hybrid's shading passes trace the camera ray where the
// pixel centre misses the claimed triangle or the pixel borders another instance or the sky
// (shaders/rt/hybrid.glsl: first_hit), so such a pixel gets the stand-alone's answer.
//
// Two passes, 32-bit image atomics only: depth (atomicMax of the key) then id (where the key
// equals the stored one, atomicMax of the id: ties between triangles resolve to the larger id,
// deterministic). Both evaluate the key with the same `precise` code, so they agree bit for bit.
// The screen bounding box only bounds the pixels tested: from the triangle clipped at
// z >= forward.w (tiny; the coverage test decides), one pixel of margin, clamped to the screen.
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

vec2 screen_of(vec3 q) {  // continuous pixel coordinates (pixel i's centre at i) of a point with z > 0
    float z = dot(q, frame.forward.xyz);
    float sx = dot(q, frame.right.xyz) / z, sy = dot(q, frame.up.xyz) / z;
    return vec2((sx / (frame.right.w * frame.up.w) + 1.0) * 0.5 * float(frame.info.x) - 0.5,
                (1.0 - sy / frame.right.w) * 0.5 * float(frame.info.y) - 0.5);
}

void extend(inout vec4 b, vec2 s) { b = vec4(min(b.xy, s), max(b.zw, s)); }

// Setup of global triangle t; false when it covers no pixel (degenerate, behind, off screen).
bool setup_triangle(uint t, out Tri tri) {
    uint instance = instance_of(t);
    uint prim = t - tri_start[instance];
    Instance I = inst[instance];
    uint base = I.info.x + 3u * prim;
    precise vec3 p0 = to_world(I, vertex_of(I.info.z + idx[base]));
    precise vec3 p1 = to_world(I, vertex_of(I.info.z + idx[base + 1u]));
    precise vec3 p2 = to_world(I, vertex_of(I.info.z + idx[base + 2u]));
    tri.id = vis_encode(instance, prim);
    tri.box = ivec4(0, 0, -1, -1);
    precise vec3 n = cross(p1 - p0, p2 - p0);
    precise float h = dot(n, p0);
    if (!(abs(h) > 0.0) || isinf(h)) return false;  // the plane passes through the camera (edge-on) or degenerate
    float s = h > 0.0 ? 1.0 : -1.0;
    precise vec3 c0 = s * cross(p1, p2), c1 = s * cross(p2, p0), c2 = s * cross(p0, p1);
    precise vec3 nh = n / h;
    precise vec3 eps = 1e-6 * vec3(length(c0), length(c1), length(c2));
    tri.c0 = c0; tri.c1 = c1; tri.c2 = c2; tri.n = nh; tri.eps = eps;
    // bounding box of the part in front of z = forward.w
    float zc = frame.forward.w;
    vec3 p[3] = vec3[3](p0, p1, p2);
    float z[3] = float[3](dot(p0, frame.forward.xyz), dot(p1, frame.forward.xyz), dot(p2, frame.forward.xyz));
    vec4 b = vec4(1e30, 1e30, -1e30, -1e30);
    for (int i = 0; i < 3; ++i) {
        int j = (i + 1) % 3;
        if (z[i] >= zc) extend(b, screen_of(p[i]));
        if ((z[i] >= zc) != (z[j] >= zc)) {
            float a = (zc - z[i]) / (z[j] - z[i]);
            extend(b, screen_of(mix(p[i], p[j], a)));
        }
    }
    if (b.x > b.z) return false;  // wholly behind the clip plane
    vec2 hi = vec2(frame.info.xy) - 1.0;
    b = vec4(clamp(floor(b.xy) - 1.0, vec2(-1.0), hi + 1.0), clamp(ceil(b.zw) + 1.0, vec2(-1.0), hi + 1.0));
    tri.box = ivec4(max(b.xy, vec2(0.0)), min(b.zw, hi));
    return tri.box.x <= tri.box.z && tri.box.y <= tri.box.w;
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

uint pixels_of(Tri tri) { return uint(tri.box.z - tri.box.x + 1) * uint(tri.box.w - tri.box.y + 1); }
