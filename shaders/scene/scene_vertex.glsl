// Vertex-shader prelude for scene geometry: inputs (scene.vertex_input) and invariant position.
//
//   #version 460
//   #include "scene/scene_vertex.glsl"
//   void main() { gl_Position = scene_clip_position(in_position, gl_InstanceIndex); ... }
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

#endif
