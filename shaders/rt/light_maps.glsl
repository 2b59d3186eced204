// Light maps of the hybrid (passes/raytrace_lightmap.py): per mapped light, the distance along
// each texel's ray from the light to the first surface (3e38: none), traced once at load by
// light_map.rgen. Point lights: six cube faces (layers 6 i .. 6 i + 5) of rays from the light;
// directional lights: up to six cascades (layers 6 i + k), parallel rays from a plane outside
// the scene's bounds over the view frustum between two depths, finest first.
// light_map_test tells, without tracing, whether a point's shadow ray is certainly unblocked
// (every ray of the 2x2 texels around the point reaches the point's own plane) or certainly
// blocked (all of them stop well before it); anything else is traced (shade.glsl: shade_local).
// Set 0 binding 16: the maps (r32f array); binding 17: 16 vec4 per mapped light (base b = 16 i):
//   point:       [b] (light position, 1)
//   directional: [b] (0, 0), [b + 1] (U, 0), [b + 2] (V, 0), [b + 3] (W ray direction, cascades),
//                cascade k: [b + 4 + 2 k] (grid corner C0, du), [b + 5 + 2 k] (0, 0, 0, dv)
#ifdef LIGHT_MAP_BUILD
layout(set = 0, binding = 16, r32f) uniform writeonly image2DArray light_maps;
#else
layout(set = 0, binding = 16, r32f) uniform readonly image2DArray light_maps;
#endif
layout(set = 0, binding = 17, std430) readonly buffer LightMapInfo { vec4 maps[]; };

const float LIGHT_MAP_FAR = 3.0e38;  // a texel whose ray hits nothing
#ifndef LIT_TOLERANCE
#define LIT_TOLERANCE 2e-4   // of the distance: the point's plane reached
#endif
#ifndef LIGHT_MAP_GUARD
#define LIGHT_MAP_GUARD 2.0  // a texel may be at most this many pixel footprints at the point
#endif
#ifndef SHADOW_MARGIN
#define SHADOW_MARGIN 0.02   // of the distance: an occluder well before the point
#endif

// Cube face `face` (2 axis + negative) at face coordinates (a, b) in [-1, 1]: a direction.
vec3 face_direction(uint face, float a, float b) {
    uint axis = face >> 1u;
    float s = (face & 1u) == 0u ? 1.0 : -1.0;
    return axis == 0u ? vec3(s, a, b) : axis == 1u ? vec3(a, s, b) : vec3(a, b, s);
}

// The cube face of direction v and its face coordinates.
uint face_of(vec3 v, out vec2 ab) {
    vec3 m = abs(v);
    if (m.x >= m.y && m.x >= m.z) { ab = v.yz / max(m.x, 1e-30); return v.x >= 0.0 ? 0u : 1u; }
    if (m.y >= m.z) { ab = v.xz / max(m.y, 1e-30); return v.y >= 0.0 ? 2u : 3u; }
    ab = v.xy / max(m.z, 1e-30); return v.z >= 0.0 ? 4u : 5u;
}

#ifndef LIGHT_MAP_BUILD
// One texel: its ray reaches the plane (distance `expected` along it) or stops well before.
void light_map_tap(float stored, float expected, inout bool clear, inout bool blocked) {
    clear = clear && stored >= expected * (1.0 - LIT_TOLERANCE);
    blocked = blocked && stored < expected * (1.0 - SHADOW_MARGIN);
}

// Mapped light `li` at point p with facing geometric normal ng (the shadow ray starts on the
// ng side) and direction to the light to_light: 1 unblocked, 0 blocked, -1 not known (trace).
// Only where a texel is no wider than LIGHT_MAP_GUARD pixel footprints at p: an occluder the
// taps miss is then narrower than a pixel there. The footprint is the pixel's cone at `path`, the
// length of the ray path from the camera to p (|p| for a camera ray's hit: the camera is at the
// origin; for a point seen in a mirror or through a pane, the whole path, as the cone spreads
// along it).
int light_map_test(uint li, vec3 p, vec3 ng, vec3 to_light, float path) {
    if (dot(ng, to_light) < 1e-3) return -1;  // the ray would start off the lit side: trace it
    ivec2 size = imageSize(light_maps).xy;
    uint b = 16u * li;
    vec4 m0 = maps[b];
    float footprint = LIGHT_MAP_GUARD * path * 2.0 * frame.right.w / float(frame.counts.y);
    bool clear = true, blocked = true;
    if (m0.w > 0.5) {
        vec3 v = p - m0.xyz;
        if (2.0 * length(v) / float(min(size.x, size.y)) > footprint) return -1;
        vec2 ab;
        uint face = face_of(v, ab);
        ivec2 c = ivec2(floor((0.5 * ab + 0.5) * vec2(size) - 0.5));  // the taps around p: c .. c + 1
        if (any(lessThan(c, ivec2(0))) || any(greaterThan(c, size - 2))) return -1;  // taps past the face
        float plane = dot(ng, v);
        for (int j = 0; j <= 1; ++j)
            for (int i = 0; i <= 1; ++i) {
                ivec2 t = c + ivec2(i, j);
                vec2 tab = 2.0 * (vec2(t) + 0.5) / vec2(size) - 1.0;
                vec3 w = normalize(face_direction(face, tab.x, tab.y));
                float den = dot(ng, w);
                if (abs(den) < 1e-3 || plane / den <= 0.0) return -1;
                light_map_tap(imageLoad(light_maps, ivec3(t, int(6u * li + face))).r, plane / den, clear, blocked);
            }
        return clear ? 1 : blocked ? 0 : -1;
    }
    vec3 U = maps[b + 1u].xyz, V = maps[b + 2u].xyz, W = maps[b + 3u].xyz;
    uint cascades = uint(maps[b + 3u].w);
    float den = dot(ng, W);
    if (abs(den) < 1e-3) return -1;
    for (uint k = 0u; k < cascades; ++k) {
        vec4 grid = maps[b + 4u + 2u * k];
        float du = grid.w, dv = maps[b + 5u + 2u * k].w;
        if (max(du, dv) > footprint) continue;  // coarser than the guard allows
        vec3 r = p - grid.xyz;
        ivec2 c = ivec2(floor(vec2(dot(r, U) / du, dot(r, V) / dv) - 0.5));
        if (any(lessThan(c, ivec2(0))) || any(greaterThan(c, size - 2))) continue;  // p outside this cascade
        for (int j = 0; j <= 1; ++j)
            for (int i = 0; i <= 1; ++i) {
                ivec2 t = c + ivec2(i, j);
                vec3 o = grid.xyz + (float(t.x) + 0.5) * du * U + (float(t.y) + 0.5) * dv * V;
                float e = dot(ng, p - o) / den;
                if (e <= 0.0) return -1;
                light_map_tap(imageLoad(light_maps, ivec3(t, int(6u * li + k))).r, e, clear, blocked);
            }
        return clear ? 1 : blocked ? 0 : -1;
    }
    return -1;
}
#endif
