#version 460
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba16f) uniform writeonly image2D dst;
layout(push_constant) uniform Push { int samples; float intensity; } pc;

// Zone plate cos(k r^2) with k chosen so that the local frequency k r / pi reaches
// 2 cycles per pixel at the farthest corner; box filter of samples^2 points per pixel.
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(dst);
    if (any(greaterThanEqual(p, size))) return;
    vec2 center = vec2(size) * 0.5;
    float k = 2.0 * 3.14159265 / length(center);
    float sum = 0.0;
    for (int y = 0; y < pc.samples; ++y) {
        for (int x = 0; x < pc.samples; ++x) {
            vec2 q = vec2(p) + (vec2(x, y) + 0.5) / float(pc.samples) - center;
            sum += 0.5 + 0.5 * cos(k * dot(q, q));
        }
    }
    float v = pc.intensity * sum / float(pc.samples * pc.samples);
    imageStore(dst, p, vec4(v, 0.8 * v, 0.6 * v, 1.0));
}
