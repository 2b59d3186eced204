#version 460
// The background cube map: each texel of the 6-layer image holds sky(direction through its
// centre), as passes/rt_model.py: sky / cube_texel_dir.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba16f) uniform writeonly image2DArray sky_out;

const vec3 ZENITH = vec3(0.20, 0.40, 0.90), HORIZON = vec3(0.75, 0.80, 0.95), GROUND = vec3(0.22, 0.20, 0.18);

vec3 sky(vec3 d) {
    return d.y >= 0.0 ? HORIZON + (ZENITH - HORIZON) * clamp(d.y, 0.0, 1.0)
                      : GROUND + (HORIZON - GROUND) * clamp(1.0 + 4.0 * d.y, 0.0, 1.0);
}

void main() {
    int size = imageSize(sky_out).x;
    ivec3 t = ivec3(gl_GlobalInvocationID.xyz);
    if (t.x >= size || t.y >= size) return;
    float sc = 2.0 * (float(t.x) + 0.5) / float(size) - 1.0, tc = 2.0 * (float(t.y) + 0.5) / float(size) - 1.0;
    vec3 d[6] = vec3[6](vec3(1.0, -tc, -sc), vec3(-1.0, -tc, sc), vec3(sc, 1.0, tc), vec3(sc, -1.0, -tc),
                        vec3(sc, -tc, 1.0), vec3(-sc, -tc, -1.0));
    imageStore(sky_out, t, vec4(sky(normalize(d[t.z])), 1.0));
}
