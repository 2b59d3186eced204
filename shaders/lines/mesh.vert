#version 460
// Mesh line vertices: xyz world position, w = colour key (hue in [0, 1); +1 for deformable meshes).
layout(location = 0) in vec4 vertex;
layout(location = 0) out vec3 color;
layout(push_constant) uniform Push { mat4 view_proj; } pc;

vec3 hue(float h) {
    return clamp(abs(fract(h + vec3(0.0, 2.0 / 3.0, 1.0 / 3.0)) * 6.0 - 3.0) - 1.0, 0.0, 1.0);
}

void main() {
    gl_Position = pc.view_proj * vec4(vertex.xyz, 1.0);
    float key = vertex.w;
    color = key >= 1.0 ? mix(vec3(1.0, 0.25, 0.2), vec3(1.0, 0.8, 0.3), fract(key))  // deformable: warm
                       : mix(vec3(0.35), hue(0.45 + 0.25 * key), 0.7);                  // rigid: cool
}
