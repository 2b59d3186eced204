#version 460
layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv;
layout(location = 2) in uvec4 joints;
layout(location = 3) in mat2 skew;        // takes locations 3 and 4

layout(location = 0) out vec2 v_uv;
layout(location = 1) flat out uint v_material;
layout(location = 2) out vec3 v_normal;

layout(set = 0, binding = 0) uniform Camera { mat4 view_proj; } camera;

void main() {
    v_uv = skew * uv;
    v_material = joints.x + joints.w;
    v_normal = normalize(position);
    gl_Position = camera.view_proj * vec4(position, 1.0);
}
