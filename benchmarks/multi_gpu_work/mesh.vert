#version 460
// A procedural mesh (benchmarks/multi_gpu_work/mesh.yaml): instance = chunk (firstInstance
// included), chunk c is strip c / 2 of sheet c % 2; a strip is a horizontal strip of the
// screen tessellated into `columns` x rows quads (two triangles each).
layout(push_constant) uniform Push {
    int triangles;  // per chunk (even)
    int chunks;
    int columns;
    int pad;
} pc;

layout(location = 0) out vec3 shade;

void main() {
    int chunk = gl_InstanceIndex;
    int sheet = chunk % 2, strip = chunk / 2, strips = (pc.chunks + 1) / 2;
    int t = gl_VertexIndex / 3, k = gl_VertexIndex % 3;
    int quads = pc.triangles / 2, rows = max(1, (quads + pc.columns - 1) / pc.columns);
    int q = t / 2, col = q % pc.columns, row = q / pc.columns;
    ivec2 c[6] = ivec2[6](ivec2(0, 0), ivec2(1, 0), ivec2(1, 1), ivec2(0, 0), ivec2(1, 1), ivec2(0, 1));
    ivec2 o = c[(t & 1) * 3 + k];
    float u = float(col + o.x) / float(pc.columns);
    float v = (float(strip) + float(row + o.y) / float(rows)) / float(strips);
    float h = sheet == 0 ? 0.5 + 0.3 * sin(6.0 * u + 4.0 * v) : 0.5 + 0.3 * cos(5.0 * u - 7.0 * v);
    shade = vec3(h, float(sheet), u);
    gl_Position = vec4((vec2(u, v) * 2.0 - 1.0) * 0.95, h, 1.0);
}
