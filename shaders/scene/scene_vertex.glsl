// Vertex-shader prelude for scene geometry: inputs (scene.vertex_input) and invariant position.
//
//   #version 460
//   #include "scene/scene_vertex.glsl"
//   void main() { uint d = gl_InstanceIndex;
//                 gl_Position = scene_clip_position(scene_vertex_position(in_position, d), d); ... }
//
// scene_vertex_position / scene_vertex_pose pose skinned draws (scene/skinning.glsl) and pass
// everything else through unchanged.
//
// Depth-only shaders `#define SCENE_POSITION_ONLY` before the include and use
// scene.position_input (location 0 only, same buffers and stride).
//
// Every pass drawing scene geometry with a depth test against the prepass depth must compute
// gl_Position exactly this way (same function, invariant) so the depths match bit for bit.

#ifndef RGRAPH_SCENE_VERTEX_GLSL
#define RGRAPH_SCENE_VERTEX_GLSL

#if defined(RGRAPH_VIEWS) && RGRAPH_VIEWS > 1
#extension GL_EXT_multiview : require
#define SCENE_VIEW_INDEX uint(gl_ViewIndex)
#endif
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

// Position and normal in one pass over the bones (the position's arithmetic is the same as
// scene_vertex_position's, so depth-only shaders using that one match bit for bit).
void scene_vertex_pose(inout vec3 object_position, inout vec3 object_normal, uint draw_index) {
    if (skin_is_skinned(draw_index)) skin_vertex(uint(gl_VertexIndex), draw_index, object_position, object_normal);
}

#endif
