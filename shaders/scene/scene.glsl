// The scene on the GPU: descriptor set 0 of every scene pass (rgraph/vk/scene_gpu.py).
//
//   #include "scene/scene.glsl"     (needs #version 460 first)
//
// Conventions
// - Camera-relative world space ("world" below): world axes, origin at the camera. The CPU
//   computes every matrix in float64 relative to the camera and casts to float32, so large
//   coordinates never reach the GPU. Right-handed, +Y up; the camera looks down -Z in view space.
// - Projection: reversed-Z with an infinite far plane: NDC depth = near / -z_view, 1 at the near
//   plane, 0 at infinity. Depth buffers clear to 0 and test GREATER_OR_EQUAL.
//   Clip Y is flipped (Vulkan framebuffer Y points down), so world +Y is up in the image.
//   Scene triangles are counter-clockwise seen from outside and stay COUNTER_CLOCKWISE in
//   Vulkan's framebuffer terms: cull=BACK with front_face=COUNTER_CLOCKWISE (the default).
// - Shadow maps (shadow.glsl): one d32 layer per shadow-casting directional light, in scene order.
//   shadow_view_proj[layer] maps camera-relative world to the light's orthographic clip space;
//   depth is reversed too: 1 nearest the light, 0 farthest; uv = ndc.xy * 0.5 + 0.5 (no flip).
// - Matrices are column-major (GLSL default); the CPU writes numpy M.T as float32.
//
// Every byte offset below is mirrored by rgraph/scene/packing.py (tests check the sizes).

#ifndef RGRAPH_SCENE_GLSL
#define RGRAPH_SCENE_GLSL

#define SCENE_MAX_SHADOW_LIGHTS 4
#ifndef RGRAPH_VIEWS
#define RGRAPH_VIEWS 1
#endif

#define LIGHT_DIRECTIONAL 0
#define LIGHT_POINT 1
#define LIGHT_SPOT 2

// binding 0, std140, 800 bytes
layout(set = 0, binding = 0, std140) uniform Frame {
    mat4 view;            //   0  camera-relative world -> view (rotation only)
    mat4 proj;            //  64  view -> clip (reversed-Z, infinite far)
    mat4 view_proj;       // 128  proj * view
    mat4 inv_view_proj;   // 192
    mat4 inv_proj;        // 256
    mat4 inv_view;        // 320  view -> camera-relative world (transpose of view)
    mat4 shadow_view_proj[SCENE_MAX_SHADOW_LIGHTS];  // 384  camera-relative world -> light clip
    vec4 viewport;        // 640  (w, h, 1/w, 1/h) of the output size
    ivec4 counts;         // 656  (lights, shadow lights, decals, point lights)
    ivec4 counts2;        // 672  (materials, draws, directional lights, deformable meshes)
    vec4 time;            // 688  (seconds = frame / 60, frame index, near, fov_y radians)
    vec4 sun_direction;   // 704  xyz: unit vector TOWARDS the first directional light; w: its shadow layer or -1
    vec4 sun_radiance;    // 720  rgb: color * intensity of that light (0 without one)
    vec4 ambient;         // 736  rgb: ambient radiance
    vec4 camera_hi;       // 752  float32(camera world position)        (for large-world reconstruction)
    vec4 camera_lo;       // 768  float32(camera - camera_hi)
    vec4 scene_bounds;    // 784  camera-relative bounding sphere of the scene: centre xyz, radius w
} frame;                  // 800

#ifndef SCENE_INSTANCES
// binding 1, std430, 144 bytes each; draws[gl_InstanceIndex] (firstInstance = draw index)
struct Draw {
    mat4 model;           //   0  object -> camera-relative world
    mat4 normal_matrix;   //  64  inverse-transpose of model's 3x3 (in a mat4; use mat3(normal_matrix))
    uvec4 info;           // 128  (material index, mesh index, flags, first bone entry)
                          //      flags: 1 = deformable, 2 = skinned (scene/skinning.glsl); bits 8..31 of a
                          //      skinned draw: its mesh's bone stride (instances); w: its skeleton's first
                          //      bone entry in a logic state (bone b at w + b * stride)
};
layout(set = 0, binding = 1, std430) readonly buffer Draws { Draw draws[]; };
#else
// GPU-driven drawing (draw.mode=gpu, rgraph/scene/instances.py): binding 1 holds the
// persistent per-instance data, written once (and again only when an instance changes);
// the draw passes get only a 32-bit instance id per draw (firstInstance). 192 bytes each.
struct Instance {
#ifdef SCENE_FLOAT64
    dvec4 translation;    //   0  float64 world translation (shaderFloat64)
#else
    uvec4 translation_bits[2];  // 0  the same float64 bits, unread without shaderFloat64
#endif
    vec4 columns[3];      //  32  object -> world 3x3 (rotation * scale) columns, w 0
    vec4 normal_columns[3];  // 80  inverse-transpose of that 3x3, columns
    uvec4 info;           // 128  as Draw.info (material, mesh, flags: 1 deformable / 2 skinned + bone stride, first bone)
    vec4 translation_hi;  // 144  xyz: float32(translation)
    vec4 translation_lo;  // 160  xyz: float32(translation - hi)
    vec4 sphere;          // 176  bounding sphere: centre offset from the translation (world axes), radius
};
layout(set = 0, binding = 1, std430) readonly buffer Instances { Instance instances[]; };

// binding 6, std430, one uvec4 per scene mesh: (index count, first index, vertex offset, 0)
layout(set = 0, binding = 6, std430) readonly buffer Meshes { uvec4 meshes[]; };
#endif

// binding 2, std430, 64 bytes each
struct Material {
    vec4 base_color;      //   0  rgb, a: opacity
    vec4 surface;         //  16  (roughness, metallic, sss, reflective)
    vec4 optics;          //  32  (refractive, ior, baked_ao, 0)
    vec4 emissive;        //  48  rgb, 0
};
layout(set = 0, binding = 2, std430) readonly buffer Materials { Material materials[]; };

// binding 3, std430, 64 bytes each: the scene's lights as authored (world space, split in
// float32 high + low parts so light_setup can form camera-relative positions precisely).
struct SceneLight {
    vec4 position_hi;     //   0  xyz: float32(world position); w: type (LIGHT_*)
    vec4 position_lo;     //  16  xyz: float32(position - hi); w: radius (m)
    vec4 direction;       //  32  xyz: unit direction the light TRAVELS (directional, spot); w: shadow layer or -1
                          //      (spot: cos of the cone's inner half-angle, full intensity inside)
    vec4 radiance;        //  48  rgb: color * intensity; w: intensity (spot: cos of the outer half-angle, 0 outside)
};
layout(set = 0, binding = 3, std430) readonly buffer SceneLights { SceneLight scene_lights[]; };

// binding 4, std430, 96 bytes each
struct Decal {
    mat4 world_to_decal;  //   0  camera-relative world -> decal box [-0.5, 0.5]^3 (projects along local z)
    vec4 color;           //  64  rgb, a: opacity
    vec4 surface;         //  80  (roughness, metallic, 0, 0)
};
layout(set = 0, binding = 4, std430) readonly buffer Decals { Decal decals[]; };

// The graph buffer `lights` (written by light_setup, read by forward as a uniform), 64 bytes
// each, std140 == std430 here. Declare it in your pass, e.g.
//   layout(set = 1, binding = 0, std140) uniform LightsBlock { Light lights[LIGHT_COUNT]; };
// with LIGHT_COUNT = max(scene.lights, 1) (the buffer holds exactly that many).
struct Light {
    vec4 position;        //   0  xyz: camera-relative world position (0 for directional); w: radius
    vec4 to_light;        //  16  xyz: unit vector towards the light (directional), minus the spot axis
                          //      (spot), 0 (point); w: type (LIGHT_*)
    vec4 radiance;        //  32  rgb: color * intensity; w: shadow layer or -1
    vec4 view;            //  48  xyz: view-space position (point/spot) or view-space to_light (directional);
                          //      w: 1 / radius^2 (point/spot), 0 (directional)
};

#if RGRAPH_VIEWS > 1
// binding 5, std140 (views=2, VK_KHR_multiview): per eye, camera-relative world -> clip and the
// eye's camera-relative position; both eyes share the Frame's rotation and projection.
layout(set = 0, binding = 5, std140) uniform Views {
    mat4 view_proj[RGRAPH_VIEWS];  //   0
    vec4 eye[RGRAPH_VIEWS];        // 128  xyz: the eye's position relative to the camera
} views;
#endif

// camera-relative world -> clip of view ``view`` (0 without multiview).
mat4 scene_view_proj(uint view) {
#if RGRAPH_VIEWS > 1
    return views.view_proj[view];
#else
    return frame.view_proj;
#endif
}

// The eye of view ``view``, camera-relative (0 without multiview): shade with eye - world.
vec3 scene_eye(uint view) {
#if RGRAPH_VIEWS > 1
    return views.eye[view].xyz;
#else
    return vec3(0.0);
#endif
}

// The one vertex-transform include point: every scene vertex shader (and the skinning and
// deformation hooks) goes through these accessors of draw/instance ``d``.
#ifdef SCENE_INSTANCES
// Camera-relative translation of instance d: float64 subtraction with shaderFloat64, else the
// float32 high/low split (hi - camera_hi) + (lo - camera_lo).
vec3 scene_translation(uint d) {
#ifdef SCENE_FLOAT64
    dvec3 camera = dvec3(frame.camera_hi.xyz) + dvec3(frame.camera_lo.xyz);
    return vec3(instances[d].translation.xyz - camera);
#else
    return (instances[d].translation_hi.xyz - frame.camera_hi.xyz) + (instances[d].translation_lo.xyz - frame.camera_lo.xyz);
#endif
}

mat3 scene_model3(uint d) {
    return mat3(instances[d].columns[0].xyz, instances[d].columns[1].xyz, instances[d].columns[2].xyz);
}

mat3 scene_normal3(uint d) {
    return mat3(instances[d].normal_columns[0].xyz, instances[d].normal_columns[1].xyz,
                instances[d].normal_columns[2].xyz);
}

uvec4 scene_info(uint d) { return instances[d].info; }

vec4 scene_world_position(vec3 object_position, uint draw_index) {
    return vec4(scene_model3(draw_index) * object_position + scene_translation(draw_index), 1.0);
}
#else
mat3 scene_normal3(uint d) { return mat3(draws[d].normal_matrix); }

uvec4 scene_info(uint d) { return draws[d].info; }

// One transform for every scene vertex shader, so that depth prepass and forward produce
// bit-identical positions (declare `invariant gl_Position;`: scene_vertex.glsl does).
vec4 scene_world_position(vec3 object_position, uint draw_index) {
    return draws[draw_index].model * vec4(object_position, 1.0);
}
#endif

vec4 scene_clip_position_of(vec3 object_position, uint draw_index, uint view) {
    return scene_view_proj(view) * scene_world_position(object_position, draw_index);
}

#ifdef SCENE_VIEW_INDEX
vec4 scene_clip_position(vec3 object_position, uint draw_index) {
    return scene_clip_position_of(object_position, draw_index, SCENE_VIEW_INDEX);
}
#else
vec4 scene_clip_position(vec3 object_position, uint draw_index) {
    return frame.view_proj * scene_world_position(object_position, draw_index);
}
#endif

vec3 scene_world_normal(vec3 object_normal, uint draw_index) {
    vec3 n = scene_normal3(draw_index) * object_normal;
    float len2 = dot(n, n);
    return len2 > 1e-30 ? n * inversesqrt(len2) : vec3(0.0, 1.0, 0.0);
}

// Reversed-Z infinite depth -> positive view distance along -z (depth 0 -> infinity).
float scene_linear_depth(float depth) {
    return frame.time.z / max(depth, 1e-30);
}

// Screen uv in [0,1]^2 (origin top-left) and depth -> camera-relative world position.
vec3 scene_world_from_depth(vec2 uv, float depth) {
    vec4 ndc = vec4(uv * 2.0 - 1.0, depth, 1.0);
    vec4 w = frame.inv_view_proj * ndc;
    return w.xyz / w.w;
}

// Screen uv and depth -> view-space position.
vec3 scene_view_from_depth(vec2 uv, float depth) {
    vec4 v = frame.inv_proj * vec4(uv * 2.0 - 1.0, depth, 1.0);
    return v.xyz / v.w;
}

#endif
