// Froxel grid of clustered forward lighting (passes/clustered.py; NumPy twin passes/clustered_ref.py).
// Needs scene/scene.glsl first. Defines: GRID_X, GRID_Y (screen tiles), SLICES (depth slices),
// TILE_X, TILE_Y (pixels per tile: ceil(output / grid)), CLUSTER_FAR (metres; <= 0: the far side
// of the scene's bounding sphere).
//
// - Tile (tx, ty) covers pixels [tx * TILE_X, (tx + 1) * TILE_X) x [ty * TILE_Y, ...).
// - Slices are exponential in view distance d = -z_view: slice k covers
//   [near * (far / near)^(k / SLICES), near * (far / near)^((k + 1) / SLICES)); the last slice
//   extends to infinity, so every visible point has a froxel.
// - A froxel's bounds are the view-space AABB of its frustum cell (8 corners), padded on every side
//   by CLUSTER_PAD times the slice's far distance (its near distance for the last, unbounded slice)
//   + CLUSTER_PAD_ABS m: assignment is conservative against float rounding of the fragment's own
//   position, slice and tile, so clustered shading equals shading every light.
#ifndef CLUSTERED_CLUSTERS_GLSL
#define CLUSTERED_CLUSTERS_GLSL

#define CLUSTER_OVERFLOW 0xFFFFFFFFu  // light_grid count of a froxel whose list did not fit
#define CLUSTER_INFINITY 1e30
#define CLUSTER_PAD 1e-4
#define CLUSTER_PAD_ABS 1e-6
#define LIGHT_MIN_RADIUS 1e-6  // light_setup's floor: the window reaches zero at max(radius, this)

float cluster_near() { return frame.time.z; }

float cluster_far() {
    float n = cluster_near();
    float f = float(CLUSTER_FAR);
    if (!(f > 0.0)) f = length(frame.scene_bounds.xyz) + frame.scene_bounds.w;
    return max(f, 2.0 * n);
}

// View distance where slice k starts (k = SLICES: infinity).
float cluster_slice_start(int k) {
    if (k >= SLICES) return CLUSTER_INFINITY;
    float n = cluster_near();
    return k <= 0 ? n : n * exp2(log2(cluster_far() / n) * float(k) / float(SLICES));
}

int cluster_slice_of(float d) {
    float n = cluster_near();
    float t = log2(max(d, n) / n) / log2(cluster_far() / n);
    return clamp(int(floor(t * float(SLICES))), 0, SLICES - 1);
}

ivec3 cluster_of(vec2 frag_coord, float view_distance) {
    ivec2 t = min(ivec2(frag_coord) / ivec2(TILE_X, TILE_Y), ivec2(GRID_X - 1, GRID_Y - 1));
    return ivec3(t, cluster_slice_of(view_distance));
}

// The padding of slice k's froxels (metres, every side).
float cluster_pad(int k) {
    float d = k + 1 < SLICES ? cluster_slice_start(k + 1) : cluster_slice_start(k);
    return CLUSTER_PAD * d + CLUSTER_PAD_ABS;
}

// Unpadded view-space AABB of froxel c: (min, max).
void cluster_bounds(ivec3 c, out vec3 lo, out vec3 hi) {
    vec2 size = frame.viewport.xy;
    vec2 p0 = vec2(c.xy * ivec2(TILE_X, TILE_Y));
    vec2 p1 = min(p0 + vec2(TILE_X, TILE_Y), size);
    vec2 n0 = p0 / size * 2.0 - 1.0, n1 = p1 / size * 2.0 - 1.0;
    float d0 = cluster_slice_start(c.z), d1 = cluster_slice_start(c.z + 1);
    vec2 inv = vec2(1.0 / frame.proj[0][0], 1.0 / frame.proj[1][1]);
    lo = vec3(CLUSTER_INFINITY);
    hi = vec3(-CLUSTER_INFINITY);
    for (int i = 0; i < 8; ++i) {
        vec2 ndc = vec2((i & 1) == 0 ? n0.x : n1.x, (i & 2) == 0 ? n0.y : n1.y);
        float d = (i & 4) == 0 ? d0 : d1;
        vec3 p = vec3(ndc * inv * d, -d);
        lo = min(lo, p);
        hi = max(hi, p);
    }
}

#endif
