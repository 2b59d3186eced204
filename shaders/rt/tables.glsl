// The scene geometry tables of the ray tracing passes and the compute visibility buffer
// (passes/raytrace_standalone.py: pack_tables), set 0 bindings 0, 1 and 3.
struct Instance {
    vec4 m0, m1, m2;   // camera-relative object -> world, rows of a 3x4
    vec4 n0, n1, n2;   // normal matrix rows
    uvec4 info;        // x: first index of the mesh in idx[], y: material, z: first vertex
};
layout(set = 0, binding = 0, std430) readonly buffer Instances { Instance inst[]; };
layout(set = 0, binding = 1, std430) readonly buffer Positions { float pos[]; };
layout(set = 0, binding = 3, std430) readonly buffer Indices { uint idx[]; };

vec3 vertex_of(uint v) { return vec3(pos[3u * v], pos[3u * v + 1u], pos[3u * v + 2u]); }
vec3 to_world(Instance I, vec3 p) { return vec3(dot(I.m0, vec4(p, 1.0)), dot(I.m1, vec4(p, 1.0)), dot(I.m2, vec4(p, 1.0))); }
