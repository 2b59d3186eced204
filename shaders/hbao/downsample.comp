#version 460
// Working-resolution depth: the NEAREST surface of each k x k block (k = 1 / hbao.scale),
// i.e. the largest reversed-Z value (see passes/hbao_ref.py for why this is the
// conservative choice). At k = 1 a copy.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D depth;
layout(set = 0, binding = 1, r32f) uniform writeonly image2D depth_quarter;
layout(push_constant) uniform Push {
    int factor;  // k: full-resolution texels per working texel along each axis
} pc;

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, imageSize(depth_quarter)))) return;
    ivec2 size = textureSize(depth, 0);
    ivec2 lo = min(q * pc.factor, size - 1);
    ivec2 hi = min(q * pc.factor + pc.factor, size);
    float nearest = 0.0;
    for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x)
            nearest = max(nearest, texelFetch(depth, ivec2(x, y), 0).r);
    imageStore(depth_quarter, q, vec4(nearest));
}
