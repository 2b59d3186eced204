#version 460
// One separable Gaussian pass along pc.dir, clamp to edge (passes/bloom_ref.py: blur).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2D dst;
layout(push_constant) uniform Push {
    ivec2 dir;          // (1, 0) horizontal, (0, 1) vertical
    int radius;         // taps -radius..radius
    float weights[29];  // normalized one-sided weights 0..radius
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    ivec2 last = textureSize(src, 0) - 1;
    vec3 c = pc.weights[0] * texelFetch(src, p, 0).rgb;
    for (int i = 1; i <= pc.radius; ++i) {
        c += pc.weights[i] * (texelFetch(src, clamp(p + i * pc.dir, ivec2(0), last), 0).rgb
                              + texelFetch(src, clamp(p - i * pc.dir, ivec2(0), last), 0).rgb);
    }
    imageStore(dst, p, vec4(c, 1.0));
}
