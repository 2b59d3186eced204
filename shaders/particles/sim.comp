#version 460
// particles_sim: one thread per particle integrates a vortex field with gravity and drag
// for pc.substeps steps of pc.dt; a particle whose age runs out (or whose state is not a
// finite live one, e.g. the buffer's first contents) respawns at a hashed position.
layout(local_size_x = 256) in;
struct Particle { vec4 pos_age; vec4 vel; };
layout(std430, set = 0, binding = 0) buffer Particles { Particle p[]; } particles;
layout(push_constant) uniform Push { uint count; uint substeps; float dt; float lifetime; } pc;

uint hash(uint x) {
    x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
    return x;
}
float unit(uint x) { return float(hash(x) >> 8) / 16777216.0; }

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 pos = particles.p[i].pos_age.xyz;
    float age = particles.p[i].pos_age.w;
    vec3 vel = particles.p[i].vel.xyz;
    for (uint s = 0u; s < pc.substeps; ++s) {
        if (!(age > 0.0 && age <= pc.lifetime) || any(isnan(pos)) || any(isinf(pos)) || any(isnan(vel))) {
            uint seed = i * 4u + floatBitsToUint(age) * 0x9e3779b9U;
            pos = vec3(unit(seed) * 2.0 - 1.0, unit(seed + 1u) * 2.0 - 1.0, unit(seed + 2u) * 2.0 - 1.0) * 0.8;
            vel = vec3(0.0);
            age = pc.lifetime * (0.25 + 0.75 * unit(seed + 3u));
        }
        vec3 swirl = vec3(-pos.y, pos.x, 0.0) * 2.0 - pos * 0.5 + vec3(0.0, -0.3, 0.0);
        vel += pc.dt * (swirl - 0.2 * vel);
        pos += pc.dt * vel;
        age -= pc.dt;
    }
    particles.p[i].pos_age = vec4(pos, age);
    particles.p[i].vel = vec4(vel, 0.0);
}
