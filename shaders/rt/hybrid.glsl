// The hybrid's view of the G-buffer (set 0 bindings 8-10): the first surface of pixel px.
#include "rt/gbuffer.glsl"
layout(set = 0, binding = 8) uniform sampler2D gbuf_depth;
layout(set = 0, binding = 9) uniform sampler2D gbuf_normal;
layout(set = 0, binding = 10) uniform usampler2D gbuf_material;

// false: nothing (the sky). p: camera-relative position from depth along the camera ray d.
bool first_surface(uvec2 px, vec3 d, out vec3 p, out vec3 n, out uint m) {
    uint id = texelFetch(gbuf_material, ivec2(px), 0).r;
    if (id == 0u) return false;
    float depth = texelFetch(gbuf_depth, ivec2(px), 0).r;   // reversed-Z infinite: near / view depth
    float view_depth = frame.forward.w / max(depth, 1e-30);
    p = d * (view_depth / dot(d, frame.forward.xyz));
    n = oct_decode(texelFetch(gbuf_normal, ivec2(px), 0).rg);
    m = id - 1u;
    return true;
}
