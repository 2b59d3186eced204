// The procedural environment (an operating room) and the equirectangular mapping of env_map.
// A pure function of direction; NumPy twin: passes/ibl_ref.py (env_radiance, equirect_*).
// Axes: +y up; equirect u = atan(x, -z) / 2pi + 0.5, v = acos(y) / pi (row 0 = straight up).
#ifndef IBL_ENVIRONMENT_GLSL
#define IBL_ENVIRONMENT_GLSL

#include "forward/brdf.glsl"  // PI

const vec3 ENV_CEILING = vec3(0.80, 0.85, 0.90);
const vec3 ENV_HORIZON = vec3(0.35, 0.42, 0.45);   // tiled walls
const vec3 ENV_FLOOR = vec3(0.10, 0.12, 0.11);
// Two surgical lamps and a wall panel: direction (unnormalised), sharpness, radiance.
const vec3 ENV_LAMP0_DIR = vec3(0.3, 1.0, 0.2);
const float ENV_LAMP0_SHARP = 200.0;
const vec3 ENV_LAMP0_RGB = vec3(40.0, 38.0, 34.0);
const vec3 ENV_LAMP1_DIR = vec3(-0.4, 0.9, -0.3);
const float ENV_LAMP1_SHARP = 120.0;
const vec3 ENV_LAMP1_RGB = vec3(22.0, 24.0, 25.0);
const vec3 ENV_PANEL_DIR = vec3(1.0, 0.15, 0.0);
const float ENV_PANEL_SHARP = 20.0;
const vec3 ENV_PANEL_RGB = vec3(1.5, 2.5, 3.0);

vec3 env_radiance(vec3 d) {
    float s = clamp(d.y, -1.0, 1.0);
    float up = max(s, 0.0);
    float down = max(-s, 0.0);
    vec3 c = ENV_HORIZON + (ENV_CEILING - ENV_HORIZON) * (up * (2.0 - up))
           + (ENV_FLOOR - ENV_HORIZON) * (down * (2.0 - down));
    c += ENV_LAMP0_RGB * exp(ENV_LAMP0_SHARP * (dot(d, normalize(ENV_LAMP0_DIR)) - 1.0));
    c += ENV_LAMP1_RGB * exp(ENV_LAMP1_SHARP * (dot(d, normalize(ENV_LAMP1_DIR)) - 1.0));
    c += ENV_PANEL_RGB * exp(ENV_PANEL_SHARP * (dot(d, normalize(ENV_PANEL_DIR)) - 1.0));
    return c;
}

vec3 equirect_dir(vec2 uv) {
    float phi = (uv.x - 0.5) * (2.0 * PI);
    float theta = uv.y * PI;
    float st = sin(theta);
    return vec3(st * sin(phi), cos(theta), -st * cos(phi));
}

vec2 equirect_uv(vec3 d) {
    return vec2(atan(d.x, -d.z) * (0.5 / PI) + 0.5, acos(clamp(d.y, -1.0, 1.0)) * (1.0 / PI));
}

#endif
