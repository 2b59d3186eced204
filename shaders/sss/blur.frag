#version 460
// Separable screen-space subsurface scattering (Jimenez et al. 2015), one direction per pass.
// passes/sss_ref.py:blur is the reference; keep the two in step.
#ifndef SAMPLES
#define SAMPLES 17
#endif
#ifndef HORIZONTAL
#define HORIZONTAL 1
#endif

layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 result;
layout(set = 0, binding = 0) uniform sampler2D color_tex;   // linear, clamp to edge
layout(set = 0, binding = 1) uniform sampler2D depth_tex;   // nearest
layout(set = 0, binding = 2) uniform sampler2D normal_sss;  // nearest; .a = SSS strength
layout(set = 0, binding = 3) uniform Kernel {
    vec4 taps[SAMPLES];  // rgb weight, a offset in [-R, R]; taps[0] is the centre
    vec4 params;         // width (world), follow depth (world), projection scale * size / 2 / 3, near
} kern;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(color_tex, 0);
    vec4 centre = texelFetch(color_tex, p, 0);
    float d = texelFetch(depth_tex, p, 0).r;
    float a = texelFetch(normal_sss, p, 0).a;
    float width = kern.params.x;
    if (a <= 0.0 || d <= 0.0 || width <= 0.0) { result = centre; return; }  // exact identity
    float near = kern.params.w;
    float z = near / d;
    float stp = width * a * kern.params.z / z;
#if HORIZONTAL
    vec2 dir = vec2(1.0, 0.0);
#else
    vec2 dir = vec2(0.0, 1.0);
#endif
    vec2 c = vec2(p) + 0.5;
    vec3 acc = centre.rgb * kern.taps[0].rgb;
    for (int i = 1; i < SAMPLES; ++i) {
        vec2 pos = c + dir * (kern.taps[i].a * stp);
        vec3 tap = texture(color_tex, pos / vec2(size)).rgb;
        ivec2 t = clamp(ivec2(floor(pos)), ivec2(0), size - 1);
        float dt = texelFetch(depth_tex, t, 0).r;
        float s = dt > 0.0 ? clamp(abs(z - near / dt) / kern.params.y, 0.0, 1.0) : 1.0;
        acc += kern.taps[i].rgb * mix(tap, centre.rgb, s);
    }
    result = vec4(acc, centre.a);
}
