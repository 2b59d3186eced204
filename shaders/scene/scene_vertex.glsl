// Vertex-shader prelude for scene geometry: inputs (scene.vertex_input) and invariant position.
//
//   #version 460
//   #include "scene/scene_vertex.glsl"
//   void main() { uint d = gl_InstanceIndex;
//                 gl_Position = scene_clip_position(scene_vertex_position(in_position, d), d); ... }
//
// scene_vertex_position / scene_vertex_normal pose skinned draws (scene/skinning.glsl) and pass
// everything else through unchanged.
//
// Depth-only shaders `#define SCENE_POSITION_ONLY` before the include and use
// scene.position_input (location 0 only, same buffers and stride).
//
// Every pass drawing scene geometry with a depth test against the prepass depth must compute
// gl_Position exactly this way (same function, invariant) so the depths match bit for bit.

#ifndef RGRAPH_SCENE_VERTEX_GLSL
#define RGRAPH_SCENE_VERTEX_GLSL

#include "scene/scene.glsl"

layout(location = 0) in vec3 in_position;  // object space
#ifndef SCENE_POSITION_ONLY
layout(location = 1) in vec3 in_normal;    // object space, unit
#endif

invariant gl_Position;

#include "scene/skinning.glsl"

vec3 scene_vertex_position(vec3 object_position, uint draw_index) {
    return skin_is_skinned(draw_index) ? skin_position(uint(gl_VertexIndex), draw_index, object_position)
                                       : object_position;
}

vec3 scene_vertex_normal(vec3 object_normal, uint draw_index) {
    if (!skin_is_skinned(draw_index)) return object_normal;
    vec3 p = vec3(0.0), n = object_normal;
    skin_vertex(uint(gl_VertexIndex), draw_index, p, n);
    return n;
}

#endif
