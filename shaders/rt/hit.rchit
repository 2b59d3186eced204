#version 460
#extension GL_EXT_ray_tracing : require
struct Hit { float t; uint instance; uint prim; vec2 bary; };
layout(location = 0) rayPayloadInEXT Hit hit;
hitAttributeEXT vec2 bary;
void main() { hit.t = gl_HitTEXT; hit.instance = uint(gl_InstanceID); hit.prim = uint(gl_PrimitiveID); hit.bary = bary; }
