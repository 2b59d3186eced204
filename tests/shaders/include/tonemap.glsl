// Shared helpers for the test shaders (included, so editing it must recompile them).
#ifndef TONEMAP_GLSL
#define TONEMAP_GLSL
vec3 tonemap(vec3 c, float exposure) { return c * exposure / (1.0 + c * exposure); }
#endif
