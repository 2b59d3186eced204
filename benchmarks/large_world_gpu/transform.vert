#version 460
// Procedural small spheres (no vertex buffer): vertex gl_VertexIndex of instance
// gl_InstanceIndex. MODE 0: camera-relative float32 (translation = origin - camera formed in
// float64 on the CPU, then float32 on the GPU); MODE 1: world-space float64 (dmat4 view-proj
// with the camera translation, dvec3 world origin), cast to float32 only at gl_Position.
#ifndef MODE
#define MODE 0
#endif
#if MODE == 1
#extension GL_ARB_gpu_shader_fp64 : require
#endif

layout(set = 0, binding = 0) uniform Transform {  // std140, 256 bytes
#if MODE == 1
    dmat4 view_proj_world;  // MODE 1: proj * view (with the camera translation), float64
    dvec4 origin_world;     // MODE 1: the cluster's world position, float64
#else
    vec4 float64_part[10];  // the same 160 bytes, unused (no Float64 capability needed)
#endif
    mat4 view_proj_rel;     // MODE 0: proj * view rotation (camera at the origin), float32
    vec4 origin_rel;        // MODE 0: cluster position - camera (formed in float64), float32
    vec4 layout_;           // triangles per instance, grid side, spacing (m), radius (m)
} u;

layout(location = 0) out vec3 normal;

const float PI = 3.14159265358979;

// Corner k (0..2) of triangle t of a UV sphere with `rings` x `segments` quads.
vec3 sphere_vertex(int t, int k, int segments, int rings) {
    int quad = t / 2, seg = quad % segments, ring = quad / segments;
    ivec2 c[6] = ivec2[6](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 0), ivec2(1, 1), ivec2(0, 1));
    ivec2 o = c[(t & 1) * 3 + k];
    float phi = 2.0 * PI * float(seg + o.x) / float(segments);
    float theta = PI * float(ring + o.y) / float(rings);
    return vec3(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
}

void main() {
    int triangles = int(u.layout_.x), side = int(u.layout_.y);
    int segments = 16, rings = max(1, triangles / 32);
    vec3 unit = sphere_vertex((gl_VertexIndex / 3) % (segments * rings * 2), gl_VertexIndex % 3, segments, rings);
    normal = unit;
    int i = gl_InstanceIndex;
    vec3 offset = vec3(float(i % side), float((i / side) % side), float(i / (side * side))) * u.layout_.z;
    vec3 local = unit * u.layout_.w + offset;  // exact-ish small numbers, the same in both modes
#if MODE == 1
    dvec4 world = dvec4(u.origin_world.xyz + dvec3(local), 1.0lf);
    gl_Position = vec4(u.view_proj_world * world);
#else
    gl_Position = u.view_proj_rel * vec4(u.origin_rel.xyz + local, 1.0);
#endif
}
