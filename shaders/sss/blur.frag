#version 460
// Screen-space subsurface scattering (Jimenez et al. 2015). passes/sss_ref.py is the
// reference (blur, blur_2d); keep the two in step.
//   default:      one direction of the separable kernel per pass (HORIZONTAL 1 or 0);
//   KERNEL_2D 1:  the non-separable 2D kernel of the same profile in one pass (TAPS taps);
//   COPY 1:       copy the colour source unchanged (the vertical pass in 2D mode).
#ifndef SAMPLES
#define SAMPLES 17
#endif
#ifndef HORIZONTAL
#define HORIZONTAL 1
#endif
#ifndef KERNEL_2D
#define KERNEL_2D 0
#endif
#ifndef TAPS
#define TAPS 1
#endif
#ifndef COPY
#define COPY 0
#endif

layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 result;
#if defined(FULLSCREEN_LAYERS) && FULLSCREEN_LAYERS > 1
// views=2 (passes/sss.py): a layer per eye, this fragment's eye from lib/fullscreen.vert
layout(location = 1) flat in int in_layer;
layout(set = 0, binding = 0) uniform sampler2DArray color_tex;   // linear, clamp to edge
layout(set = 0, binding = 1) uniform sampler2DArray depth_tex;   // nearest
layout(set = 0, binding = 2) uniform sampler2DArray normal_sss;  // nearest; .a = SSS strength
#define TEXEL(t, p) texelFetch(t, ivec3(p, in_layer), 0)
#define COLOR_AT(uv) texture(color_tex, vec3(uv, float(in_layer)))
#define COLOR_SIZE() textureSize(color_tex, 0).xy
#else
layout(set = 0, binding = 0) uniform sampler2D color_tex;   // linear, clamp to edge
layout(set = 0, binding = 1) uniform sampler2D depth_tex;   // nearest
layout(set = 0, binding = 2) uniform sampler2D normal_sss;  // nearest; .a = SSS strength
#define TEXEL(t, p) texelFetch(t, p, 0)
#define COLOR_AT(uv) texture(color_tex, uv)
#define COLOR_SIZE() textureSize(color_tex, 0)
#endif
#if KERNEL_2D
layout(set = 0, binding = 3) uniform Kernel {
    vec4 taps[2 * TAPS];  // [2i] rgb weight, [2i + 1] xy offset in [-R, R]^2; tap 0 is the centre
    vec4 params;          // width (world), follow depth (world), P00 * width_px / 2 / 3, near
    vec4 params2;         // P11 * height_px / 2 / 3, -, -, -
} kern;
#else
layout(set = 0, binding = 3) uniform Kernel {
    vec4 taps[SAMPLES];  // rgb weight, a offset in [-R, R]; taps[0] is the centre
    vec4 params;         // width (world), follow depth (world), projection scale * size / 2 / 3, near
} kern;
#endif

// The tap's colour lerped toward the centre's by the depth difference (follow-surface).
vec3 follow(vec2 pos, ivec2 size, float z, vec3 centre) {
    vec3 tap = COLOR_AT(pos / vec2(size)).rgb;
    ivec2 t = clamp(ivec2(floor(pos)), ivec2(0), size - 1);
    float dt = TEXEL(depth_tex, t).r;
    float s = dt > 0.0 ? clamp(abs(z - kern.params.w / dt) / kern.params.y, 0.0, 1.0) : 1.0;
    return mix(tap, centre, s);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
#if COPY
    result = TEXEL(color_tex, p);
#else
    ivec2 size = COLOR_SIZE();
    vec4 centre = TEXEL(color_tex, p);
    float d = TEXEL(depth_tex, p).r;
    float a = TEXEL(normal_sss, p).a;
    float width = kern.params.x;
    if (a <= 0.0 || d <= 0.0 || width <= 0.0) { result = centre; return; }  // exact identity
    float z = kern.params.w / d;
    vec2 c = vec2(p) + 0.5;
    vec3 acc = centre.rgb * kern.taps[0].rgb;
#if KERNEL_2D
    vec2 stp = width * a * vec2(kern.params.z, kern.params2.x) / z;
    for (int i = 1; i < TAPS; ++i)
        acc += kern.taps[2 * i].rgb * follow(c + kern.taps[2 * i + 1].xy * stp, size, z, centre.rgb);
#else
    float stp = width * a * kern.params.z / z;
#if HORIZONTAL
    vec2 dir = vec2(1.0, 0.0);
#else
    vec2 dir = vec2(0.0, 1.0);
#endif
    for (int i = 1; i < SAMPLES; ++i)
        acc += kern.taps[i].rgb * follow(c + dir * (kern.taps[i].a * stp), size, z, centre.rgb);
#endif
    result = vec4(acc, centre.a);
#endif
}
