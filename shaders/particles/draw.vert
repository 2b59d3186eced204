#version 460
#if defined(PARTICLE_LAYERS) && PARTICLE_LAYERS > 1
#extension GL_ARB_shader_viewport_layer_array : require
#endif
// particles_draw: one point per particle (no vertex buffer), orthographic on x-y.
// PARTICLE_LAYERS = n (views=2): one instance per layer of a layered framebuffer, the same points
// in every layer (the projection has no camera, so both eyes see them alike).
struct Particle { vec4 pos_age; vec4 vel; };
layout(std430, set = 0, binding = 0) readonly buffer Particles { Particle p[]; } particles;
layout(location = 0) out vec3 out_color;

void main() {
    vec4 pa = particles.p[gl_VertexIndex].pos_age;
    bool live = pa.w > 0.0 && all(lessThan(abs(pa.xy), vec2(4.0)));
    gl_Position = live ? vec4(pa.xy * 0.5, 0.5, 1.0) : vec4(2.0, 2.0, 0.5, 1.0);  // outside: clipped
    gl_PointSize = 1.0;
    float speed = length(particles.p[gl_VertexIndex].vel.xyz);
    out_color = vec3(0.02, 0.03, 0.05) * (1.0 + min(speed, 4.0));
#if defined(PARTICLE_LAYERS) && PARTICLE_LAYERS > 1
    gl_Layer = gl_InstanceIndex;
#endif
}
