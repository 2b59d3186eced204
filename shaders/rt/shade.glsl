// The ray tree (needs payloads `hit` at location 0 and `visible` at location 1), walked depth
// first with an explicit stack: passes/rt_ref.py trace_pixel, line for line.
// With LIGHT_MAPS (the hybrid) shadow rays are traced only where light_maps.glsl cannot tell.
const uint MAX_STACK = 17u;
#ifdef LIGHT_MAPS
#include "light_maps.glsl"
#endif

// path: the length of the path from the camera to o (0 for camera rays): with the ray's own t the
// distance a hit's pixel footprint grows over (flat mirrors and panes keep a pixel's cone angle).
struct Ray { vec3 o; vec3 d; vec3 w; uint depth; float path; };
Ray stack[MAX_STACK];
uint top = 0u;

#ifdef NO_TRACE
// Without ray tracing (hybrid_first.comp): a shadow ray the light maps cannot decide is not
// traced; it marks the point `undecided`, and the caller hands the pixel to the ray tracing pass.
bool undecided = false;
bool lit(vec3 o, vec3 d, float dist) { undecided = true; return false; }
#else
Hit trace_closest(vec3 o, vec3 d) {
    hit.t = -1.0;
    traceRayEXT(tlas, gl_RayFlagsOpaqueEXT, 0xFF, 0, 0, 0, o, 0.0, d, T_MAX, 0);
    return hit;
}

bool lit(vec3 o, vec3 d, float dist) {
    visible = 0u;
    traceRayEXT(tlas, gl_RayFlagsOpaqueEXT | gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT,
                0xFF, 0, 0, 1, o, 0.0, d, dist, 1);
    return visible != 0u;
}
#endif

vec3 shade_local(vec3 p, vec3 ng, vec3 ns, vec3 d, uint m, float path) {
    vec3 albedo = mat[2u * m].rgb;
    float ks = mat[2u * m].w, shininess = mat[2u * m + 1u].w;
    vec3 c = AMBIENT * albedo;
    vec3 o = offset_ray(p, ng);
    for (uint i = 0u; i < frame.counts.w; ++i) {
        vec4 l = lights[2u * i];
        vec3 radiance = lights[2u * i + 1u].rgb;
        vec3 to_light; float dist, falloff;
        if (l.w < 0.5) { to_light = normalize(l.xyz); dist = T_MAX; falloff = 1.0; }
        else { vec3 rel = l.xyz - p; dist = length(rel); to_light = rel / max(dist, 1e-20); falloff = 1.0 / max(dist * dist, 1e-8); }
        float n_dot_l = dot(ns, to_light);
        if (n_dot_l <= 0.0) continue;
#ifdef LIGHT_MAPS
        int known = i < MAPPED_LIGHTS ? light_map_test(i, p, ng, to_light, path) : -1;
        if (known == 0 || (known < 0 && !lit(o, to_light, dist))) continue;
#else
        if (!lit(o, to_light, dist)) continue;
#endif
        vec3 r = 2.0 * n_dot_l * ns - to_light;
        float spec = ks * pow(max(dot(r, -d), 0.0), shininess);
        c += radiance * falloff * (albedo * n_dot_l + spec);
    }
    return c;
}

// Push the reflection/refraction rays of a surface hit by `r` (facing normals ngf/nsf).
void push_children(Ray r, vec3 p, vec3 ngf, vec3 nsf, bool entering, uint m, float path) {
    if (r.depth + 1u >= frame.counts.z || top + 2u > MAX_STACK) return;
    vec4 k = mat[2u * m + 1u];  // kr kt ior n
    vec3 reflect_w = r.w * k.x;
    if (k.y > 0.0) {
        float eta = entering ? 1.0 / k.z : k.z;
        // sin^2 of the incidence angle and the tangential part of r.d from cross products, not
        // 1 - cos^2 and r.d + cos * n: those cancel near normal incidence, where a large eta
        // (glass of index 1000 seen from inside) needs sin^2 to float32 precision to tell
        // total internal reflection from refraction
        vec3 side = cross(r.d, nsf);
        float kk = 1.0 - eta * eta * dot(side, side);
        if (kk < 0.0) reflect_w += r.w * k.y;  // total internal reflection
        else {
            vec3 t = eta * cross(nsf, side) - sqrt(kk) * nsf;
            stack[top++] = Ray(offset_ray(p, -ngf), safe_normalize(t, r.d), r.w * k.y * mat[2u * m].rgb, r.depth + 1u, path);
        }
    }
    if (max(reflect_w.x, max(reflect_w.y, reflect_w.z)) > 0.0) {
        vec3 refl = r.d - 2.0 * dot(r.d, nsf) * nsf;
        stack[top++] = Ray(offset_ray(p, ngf), safe_normalize(refl, ngf), reflect_w, r.depth + 1u, path);
    }
}

// Ray r's hit h (found by tracing or, for the hybrid's camera rays, from the visibility
// buffer): its weighted opaque radiance added to `color`, its children pushed on the stack.
void shade_hit(Ray r, Hit h, inout vec3 color) {
    vec3 p = r.o + h.t * r.d;
    float path = r.path + h.t;
    vec3 ng, ns; uint m;
    surface(h, r.d, ng, ns, m);
    bool entering = dot(r.d, ng) < 0.0;
    vec3 ngf = entering ? ng : -ng, nsf = entering ? ns : -ns;
    vec4 k = mat[2u * m + 1u];
    float opaque = 1.0 - k.x - k.y;
    if (opaque > 0.0) color += r.w * opaque * shade_local(p, ngf, nsf, r.d, m, path);
    push_children(r, p, ngf, nsf, entering, m, path);
}

#ifndef NO_TRACE
// One node of the ray tree: ray r's closest hit; adds its own radiance (the sky where it misses,
// else the weighted opaque part) to `color` and pushes its children on the stack. The hybrid's
// wavefront passes (hybrid_wave.rgen) run it once per listed ray.
void visit(Ray r, inout vec3 color) {
    Hit h = trace_closest(r.o, r.d);
    if (h.t < 0.0) { color += r.w * sample_sky(r.d); return; }
    shade_hit(r, h, color);
}

// Radiance of every ray on the stack and of their descendants.
vec3 walk() {
    vec3 color = vec3(0.0);
    while (top > 0u) visit(stack[--top], color);
    return color;
}
#endif

vec3 camera_ray(uvec2 px) {
    float sx = (2.0 * (float(px.x) + 0.5) / float(frame.counts.x) - 1.0) * frame.right.w * frame.up.w;
    float sy = (1.0 - 2.0 * (float(px.y) + 0.5) / float(frame.counts.y)) * frame.right.w;
    return normalize(frame.forward.xyz + sx * frame.right.xyz + sy * frame.up.xyz);
}
