// Skinning in the vertex shader (rgraph/vk/skin_gpu.py, rgraph/scene/skinning.py): set 0
// bindings 7-9 of the scene (after scene.glsl's Views 5 and Meshes 6). Included by scene/scene_vertex.glsl (needs scene/scene.glsl).
//
// A skinned draw (Draw.info.z & 2) reads, per vertex, 4 joints (uint8) and 4 weights (unorm8)
// from SkinVertices[vertex index]; bone b of the draw's skeleton is entry
// info.w + b * (info.z >> 8) of a logic state. Each bone is 8 half floats (t.xyz, s, q.xyzw), the
// joint transform x -> t + s * rotate(q, x) (rest joint frame to posed). Two logic states (the
// study's two bone textures: slots of the Bones ring) are interpolated at SkinFrame.alpha: lerp
// of t and s, shortest-arc normalised lerp of q (q1 negated when dot(q0, q1) < 0) - as
// rgraph.scene.skinning.interpolate - then the inverse bind: a rest vertex p moves to
// t + s * rotate(q, p - head) (head: the bone's rest joint, float32, in the Bones header at
// bones[info.y].x + b). Linear blend: the influences' results weighted; normals rotated,
// weighted (renormalise after the normal matrix).

#ifndef RGRAPH_SKINNING_GLSL
#define RGRAPH_SKINNING_GLSL

#define DRAW_SKINNED 2u
#ifndef SKIN_ALPHA
#define SKIN_ALPHA skin_frame.alpha  // the interpolation factor (a test shader may override it)
#endif

layout(set = 0, binding = 7, std430) readonly buffer SkinVertices { uvec2 skin_vertices[]; };
layout(set = 0, binding = 8, std430) readonly buffer Bones { uvec4 bones[]; };
layout(set = 0, binding = 9, std140) uniform SkinFrame {
    float alpha;          // 0: previous state, 1: current
    uint previous;        // first entry of the previous state's slot in bones[]
    uint current;         // first entry of the current state's slot
    uint pad;
} skin_frame;

struct SkinBone {
    vec4 q;
    vec3 t;
    float s;
};

SkinBone skin_unpack(uvec4 u) {
    vec2 a = unpackHalf2x16(u.x), b = unpackHalf2x16(u.y), c = unpackHalf2x16(u.z), d = unpackHalf2x16(u.w);
    return SkinBone(vec4(c, d), vec3(a, b.x), b.y);
}

// Entry `entry` of the logic state, interpolated between the previous and the current state.
SkinBone skin_bone(uint entry) {
    SkinBone a = skin_unpack(bones[skin_frame.previous + entry]);
    SkinBone b = skin_unpack(bones[skin_frame.current + entry]);
    float alpha = SKIN_ALPHA;
    vec4 q1 = dot(a.q, b.q) < 0.0 ? -b.q : b.q;
    vec4 q = a.q + alpha * (q1 - a.q);
    float len2 = dot(q, q);
    q = len2 > 1e-30 ? q * inversesqrt(len2) : vec4(0.0, 0.0, 0.0, 1.0);
    return SkinBone(q, a.t + alpha * (b.t - a.t), a.s + alpha * (b.s - a.s));
}

vec3 skin_rotate(vec4 q, vec3 v) {
    vec3 c = 2.0 * cross(q.xyz, v);
    return v + q.w * c + cross(q.xyz, c);
}

bool skin_is_skinned(uint draw_index) {
    return (scene_info(draw_index).z & DRAW_SKINNED) != 0u;
}

// Posed object-space position (and normal, unnormalised) of vertex `vertex` of a skinned draw.
void skin_vertex(uint vertex, uint draw_index, inout vec3 position, inout vec3 normal) {
    uvec2 sv = skin_vertices[vertex];
    vec4 w = unpackUnorm4x8(sv.y);
    uvec4 info = scene_info(draw_index);  // Draw.info or Instance.info (draw.mode=gpu): same fields
    uint stride = info.z >> 8u, first = info.w;
    uint heads = bones[info.y].x;
    vec3 p = vec3(0.0), n = vec3(0.0);
    for (uint k = 0u; k < 4u; ++k) {
        if (w[k] == 0.0) continue;
        uint joint = (sv.x >> (8u * k)) & 0xFFu;
        SkinBone b = skin_bone(first + joint * stride);
        vec3 head = uintBitsToFloat(bones[heads + joint].xyz);
        p += w[k] * (b.t + b.s * skin_rotate(b.q, position - head));
        n += w[k] * skin_rotate(b.q, normal);
    }
    position = p;
    normal = n;
}

vec3 skin_position(uint vertex, uint draw_index, vec3 position) {
    vec3 normal = vec3(0.0);
    skin_vertex(vertex, draw_index, position, normal);
    return position;
}

#endif
