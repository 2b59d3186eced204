#version 460
// Per-pixel-heavy full-screen shading (benchmarks/multi_gpu_work/pixels.yaml): ITERATIONS steps
// of a Julia map folded back inside radius 2, no early exit (uniform cost per pixel).
#ifndef ITERATIONS
#define ITERATIONS 256
#endif
layout(location = 0) in vec2 uv;
layout(location = 0) out vec4 color;

void main() {
    vec2 z = (uv - 0.5) * vec2(3.2, 1.8);
    const vec2 c = vec2(-0.8, 0.156);
    float acc = 0.0;
    for (int i = 0; i < ITERATIONS; ++i) {
        z = vec2(z.x * z.x - z.y * z.y, 2.0 * z.x * z.y) + c;
        float r = dot(z, z);
        acc += exp(-r);
        z = r > 4.0 ? z / r : z;
    }
    color = vec4(fract(acc * 0.05), fract(acc * 0.013), 0.5 + 0.5 * sin(acc * 0.01), 1.0);
}
