#version 460
layout(location = 0) in vec2 v_uv;
layout(location = 1) flat in uint v_material;
layout(location = 2) in vec3 v_normal;

layout(set = 0, binding = 1) uniform sampler2D textures[4];
layout(set = 0, binding = 2) uniform texture2D shadow_map;
layout(set = 0, binding = 3) uniform sampler shadow_sampler;
layout(input_attachment_index = 0, set = 1, binding = 0) uniform subpassInput gbuffer;

layout(location = 0) out vec4 color;
layout(location = 1) out uvec2 ids;
layout(location = 3) out float depth_out;

void main() {
    vec4 t = texture(textures[v_material & 3u], v_uv);
    float s = texture(sampler2D(shadow_map, shadow_sampler), v_uv).r;
    color = t * s + subpassLoad(gbuffer);
    ids = uvec2(v_material, 7u);
    depth_out = v_normal.z;
}
