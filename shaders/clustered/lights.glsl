// Physically bounded lights of the clustered passes (NumPy twin: passes/clustered_ref.py).
// Needs scene/scene.glsl, forward/brdf.glsl and the `lights` array (Light[]) declared first.
//
// Point and spot lights: inverse square windowed to reach exactly zero at the radius (Karis 2013),
//   falloff = clamp(1 - (d^2 / r^2)^2, 0, 1)^2 / max(d^2, 1e-6),  r = max(radius, 1e-6);
// spot lights also: t = clamp((cos - cos_outer) / max(cos_inner - cos_outer, 1e-4), 0, 1), factor t^2,
// zero outside the outer cone. So a light contributes nothing outside its sphere (and cone):
// shading only the lights whose bounds meet a froxel equals shading every light.
#ifndef CLUSTERED_LIGHTS_GLSL
#define CLUSTERED_LIGHTS_GLSL

float light_window(float dist2, float inv_r2) {
    float x = dist2 * inv_r2;
    float w = clamp(1.0 - x * x, 0.0, 1.0);
    return w * w / max(dist2, 1e-6);
}

float spot_factor(float cos_angle, float cos_inner, float cos_outer) {
    float t = clamp((cos_angle - cos_outer) / max(cos_inner - cos_outer, 1e-4), 0.0, 1.0);
    return t * t;
}

// Adds light i (the graph buffer `lights`, cones from the scene's SceneLights) at world point p.
void shade_light(uint i, Surface s, vec3 p, inout vec3 diffuse, inout vec3 specular) {
    Light light = lights[i];
    int type = int(light.to_light.w + 0.5);
    vec3 radiance = light.radiance.rgb;
    vec3 l;
    if (type == LIGHT_DIRECTIONAL) {
        l = safe_normalize(light.to_light.xyz, s.n);
    } else {
        vec3 d = light.position.xyz - p;
        float dist2 = dot(d, d);
        l = safe_normalize(d, s.n);
        radiance *= light_window(dist2, light.view.w);
        if (type == LIGHT_SPOT) {
            SceneLight sl = scene_lights[i];
            radiance *= spot_factor(dot(l, light.to_light.xyz), sl.direction.w, sl.radiance.w);
        }
    }
    eval_light(s, l, radiance, diffuse, specular);
}

#endif
