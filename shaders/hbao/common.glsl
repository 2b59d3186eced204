// Shared by the HBAO shaders: view-space reconstruction from reversed-Z, infinite-far depth.
// proj = (P00, P11, near, unused): clip = (P00 x, P11 y, near, -z), depth = near / -z, sky = 0.
#ifndef HBAO_COMMON_GLSL
#define HBAO_COMMON_GLSL

vec3 view_position(float depth, vec2 uv, vec4 proj) {
    float z = proj.z / depth;
    vec2 ndc = uv * 2.0 - 1.0;
    return vec3(ndc.x * z / proj.x, ndc.y * z / proj.y, -z);
}

#endif
