// Low-discrepancy GGX importance sampling (Karis 2013). NumPy twin: passes/ibl_ref.py.
#ifndef IBL_SAMPLING_GLSL
#define IBL_SAMPLING_GLSL

vec2 hammersley(uint i, uint n) {
    return vec2(float(i) / float(n), float(bitfieldReverse(i)) * 2.3283064365386963e-10);
}

// A half vector around +z (tangent space) for GGX with the given alpha.
vec3 ggx_sample_tangent(vec2 xi, float alpha) {
    float phi = 2.0 * PI * xi.x;
    float a2 = alpha * alpha;
    float cos_t = sqrt(clamp((1.0 - xi.y) / (1.0 + (a2 - 1.0) * xi.y), 0.0, 1.0));
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    return vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Orthonormal basis around unit n, valid for every n including the poles
// (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
void onb(vec3 n, out vec3 t, out vec3 b) {
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + sgn * n.x * n.x * a, sgn * c, -sgn * n.x);
    b = vec3(c, sgn + n.y * n.y * a, -n.y);
}

#endif
