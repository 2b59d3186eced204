#version 460
#extension GL_EXT_ray_tracing : require
struct Hit { float t; uint instance; uint prim; vec2 bary; };
layout(location = 0) rayPayloadInEXT Hit hit;
void main() { hit.t = -1.0; }
