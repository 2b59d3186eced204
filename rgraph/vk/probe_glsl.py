"""Generate the probe's GLSL for one plan pass (pure: no ``vulkan`` import).

Bindings (set 0), in order: one combined image sampler per ``sampled`` access (a 2D-array
view of its range), one storage image per (storage access, mip) (a 2D-array view of its
layers), one storage buffer per storage buffer access, one uniform buffer per ``uniform``
access, then one acceleration structure per ``accel_read`` access (compute and raster passes:
ray queries, the probe's rays of ``rgraph.vk.probe_rt_glsl`` in the compute shader or in each
raster stage the access declares, like reads). Vertex buffers feed one ``uint`` attribute each
(stride 0). See ``rgraph.probe.semantics`` for what is computed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rgraph import formats
from rgraph.probe.semantics import MISS_VALUE, analyze, mip_extent, raster_read_stages
from rgraph.probe.values import HEADER_WORDS, Codec, codec, has_header, header_words, modulus
from rgraph.vk.errors import ExecutionError

STORAGE = ("storage_read", "storage_write", "storage_rw")
#: (origin, direction) of the probe's rays, in the probe geometry's space
#: (``rgraph.vk.accel.probe_geometry``): one hits instance 0, one instance 1, one misses.
PROBE_RAYS = (((0.25, 0.5, -1.0), (0.0, 0.0, 1.0)), ((3.25, 0.5, -1.0), (0.0, 0.0, 1.0)),
              ((0.25, 0.5, -1.0), (0.0, 0.0, -1.0)))


def vec3(t: tuple[float, float, float]) -> str:
    return "vec3(" + ", ".join(repr(float(x)) for x in t) + ")"


def ray_query_lines(binding: int, indent: str) -> list[str]:
    """The probe's rays against accel ``as{binding}`` as ray queries, each adding to ``s`` what
    the ray tracing probe's closest-hit / miss shaders return."""
    lines = []
    for origin, direction in PROBE_RAYS:
        lines += [f"{indent}{{ rayQueryEXT q; rayQueryInitializeEXT(q, as{binding}, gl_RayFlagsOpaqueEXT, 0xFFu, "
                  f"{vec3(origin)}, 0.0, {vec3(direction)}, 100.0);",
                  f"{indent}  while (rayQueryProceedEXT(q)) {{}}",
                  f"{indent}  s += rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionTriangleEXT"
                  f" ? uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, true)) + 1u : {MISS_VALUE}u; }}"]
    return lines


@dataclass
class BindingSpec:
    binding: int
    kind: str  # sampled | storage_image | storage_buffer | uniform_buffer
    access: int
    mip: int | None = None  # storage images: absolute mip of the view


@dataclass
class ProbeShaders:
    kind: str  # compute | raster
    sources: dict[str, str]  # stage ("comp" | "vert" | "frag") -> GLSL
    bindings: list[BindingSpec]
    domain: tuple[int, int]  # compute: texels covered; raster: render area
    color_accesses: list[int] = field(default_factory=list)
    depth_access: int | None = None
    vertex_accesses: list[int] = field(default_factory=list)
    index_accesses: list[int] = field(default_factory=list)
    indirect_accesses: list[int] = field(default_factory=list)
    layer_count: int = 1  # raster: render-pass instances (one per attachment layer)


def _prefix(resource: dict) -> str:
    c = codec(resource["format"])
    if c:
        return c.glsl_prefix
    numeric = formats.lookup(resource["format"]).numeric
    return {"UINT": "u", "SINT": "i"}.get(numeric, "")


def _decode(c: Codec | None, expr: str) -> str:
    if c is None:
        return f"uint({expr}.r)"
    if c.kind in ("uint",):
        return f"{expr}.r"
    if c.kind == "sint":
        return f"uint({expr}.r)"
    if c.kind == "srgb":
        return f"probe_dec_srgb({expr}.r)"
    if c.kind == "sfloat":
        return f"uint(round({expr}.r))"
    return f"probe_dec_scaled({expr}.r, {1.0 / c.scale!r})"


def _encode(c: Codec | None, v: str) -> str:
    if c is None:
        return "vec4(0.5)"
    if c.kind == "uint":
        return f"uvec4({v})"
    if c.kind == "sint":
        return f"ivec4(int({v}))"
    if c.kind == "srgb":
        return f"probe_enc_srgb({v})"
    if c.kind == "sfloat":
        return f"vec4(float({v}))"
    return f"probe_enc_scaled({v}, {c.scale!r})"


def _storage_qualifier(resource: dict) -> str:
    spirv = formats.lookup(resource["format"]).spirv_image_format
    if not spirv:
        raise ExecutionError(f"resource {resource['name']!r}: format {resource['format']} cannot be a storage image")
    special = {"R11fG11fB10f": "r11f_g11f_b10f", "Rgb10A2": "rgb10_a2", "Rgb10a2ui": "rgb10_a2ui"}
    if spirv in special:
        return special[spirv]
    q = spirv.lower()
    return q.replace("snorm", "_snorm")


def _words(resource: dict) -> int:
    n = int(resource.get("size_bytes") or resource["bytes"]) // 4
    minimum = HEADER_WORDS + 1 if has_header(resource) else 1
    if n < minimum:
        raise ExecutionError(f"buffer {resource['name']!r} is too small for the probe ({n * 4} bytes; it needs at "
                             f"least {4 * minimum} bytes{' for its indirect-argument header' if minimum > 1 else ''})")
    return n


def generate(plan_pass: dict, resources: dict[str, dict], plan_size: tuple[int, int],
             ray_queries: bool = True) -> ProbeShaders:
    """The probe shaders of a compute or raster pass (``ray_queries=False``: no accel bindings,
    the ray tracing probe adds its own)."""
    kind = plan_pass["kind"]
    if kind not in ("compute", "raster"):
        raise ExecutionError(f"pass {plan_pass['name']!r}: the probe has no shaders for kind {kind!r}")
    accesses = plan_pass["accesses"]
    probe = analyze(plan_pass, resources)
    bindings: list[BindingSpec] = []
    decls: list[str] = []
    by_access: dict[tuple[int, int | None], int] = {}
    for i, a in enumerate(accesses):
        res = resources[a["resource"]]
        usage = a["usage"]
        if res.get("samples", 1) != 1 and res["kind"] == "image":
            raise ExecutionError(f"resource {res['name']!r}: the probe does not handle multisampled images")
        if usage == "sampled":
            b = len(bindings)
            bindings.append(BindingSpec(b, "sampled", i))
            decls.append(f"layout(set=0, binding={b}) uniform {_prefix(res)}sampler2DArray t{b};")
            by_access[(i, None)] = b
        elif usage in STORAGE and res["kind"] == "image":
            q = _storage_qualifier(res)
            for m in range(*a["subresource"]["mips"]):
                b = len(bindings)
                bindings.append(BindingSpec(b, "storage_image", i, m))
                decls.append(f"layout(set=0, binding={b}, {q}) uniform {_prefix(res)}image2DArray img{b};")
                by_access[(i, m)] = b
        elif usage in STORAGE:
            b = len(bindings)
            bindings.append(BindingSpec(b, "storage_buffer", i))
            decls.append(f"layout(set=0, binding={b}, std430) buffer B{b} {{ uint w[]; }} buf{b};")
            by_access[(i, None)] = b
        elif usage == "uniform":
            b = len(bindings)
            n = min(max(int(res.get("size_bytes") or res["bytes"]) // 16, 1), 4096)
            bindings.append(BindingSpec(b, "uniform_buffer", i))
            decls.append(f"layout(set=0, binding={b}, std140) uniform U{b} {{ uvec4 w[{n}]; }} ubo{b};")
            by_access[(i, None)] = b
    accels = []
    for i, a in enumerate(accesses):
        if a["usage"] == "accel_read" and ray_queries:
            b = len(bindings)
            bindings.append(BindingSpec(b, "accel", i))
            decls.append(f"layout(set=0, binding={b}) uniform accelerationStructureEXT as{b};")
            accels.append(b)

    def read_expr(access_index: int, sub, stage: str, xy: str) -> str:
        a = accesses[access_index]
        res = resources[a["resource"]]
        if res["kind"] == "buffer":
            b = by_access[(access_index, None)]
            hdr = HEADER_WORDS if has_header(res) else 0
            if a["usage"] == "uniform":
                return f"ubo{b}.w[{hdr // 4}].x"
            n = _words(res)
            lin = "0u" if stage == "vertex" else f"(({xy}.y * {domain[0]}u + {xy}.x) % {n - hdr}u)"
            return f"buf{b}.w[{hdr}u + {lin}]"
        mip, layer = sub
        w, h = mip_extent(res, mip)
        c = codec(res["format"])
        coord = "ivec2(0)" if stage == "vertex" else f"ivec2({xy}.x % {w}u, {xy}.y % {h}u)"
        rel_layer = layer - a["subresource"]["layers"][0]
        if a["usage"] == "sampled":
            b = by_access[(access_index, None)]
            rel_mip = mip - a["subresource"]["mips"][0]
            return _decode(c, f"texelFetch(t{b}, ivec3({coord}, {rel_layer}), {rel_mip})")
        b = by_access[(access_index, mip)]
        return _decode(c, f"imageLoad(img{b}, ivec3({coord}, {rel_layer}))")

    # Domain: compute covers every written/read image texel; raster renders the attachment extent.
    image_extents = []
    for a in accesses:
        res = resources[a["resource"]]
        if res["kind"] == "image":
            image_extents += [mip_extent(res, m) for m in range(*a["subresource"]["mips"])]
    attachments = [i for i, a in enumerate(accesses)
                   if a["usage"] in ("color_attachment", "color_attachment_blend", "depth_attachment", "depth_read")]
    if kind == "raster" and attachments:
        extents = set()
        layer_counts = set()
        for i in attachments:
            a = accesses[i]
            mips, layers = a["subresource"]["mips"], a["subresource"]["layers"]
            if mips[1] - mips[0] != 1:
                raise ExecutionError(f"pass {plan_pass['name']!r}: an attachment must cover one mip level")
            extents.add(mip_extent(resources[a["resource"]], mips[0]))
            layer_counts.add(layers[1] - layers[0])
        if len(extents) != 1 or len(layer_counts) != 1:
            raise ExecutionError(f"pass {plan_pass['name']!r}: attachments differ in extent or layer count")
        domain = extents.pop()
        layer_count = layer_counts.pop()
    else:
        domain = (max(e[0] for e in image_extents), max(e[1] for e in image_extents)) if image_extents else (64, 1)
        layer_count = 1
    if kind == "raster":
        for a in accesses:
            res = resources[a["resource"]]
            if a["usage"] in ("storage_write", "storage_rw") and res["kind"] == "image":
                for m in range(*a["subresource"]["mips"]):
                    if mip_extent(res, m)[0] > domain[0] or mip_extent(res, m)[1] > domain[1]:
                        raise ExecutionError(
                            f"pass {plan_pass['name']!r}: storage image {res['name']!r} is larger than the render area")
            if a["usage"] == "storage_rw" and layer_count > 1:
                raise ExecutionError(f"pass {plan_pass['name']!r}: storage_rw with layered attachments is not probed")

    def write_block(write, total: str, xy: str, domain_expr: str) -> list[str]:
        a = accesses[write.access]
        res = resources[a["resource"]]
        m = modulus(res)
        lines = []
        if res["kind"] == "buffer":
            b = by_access[(write.access, None)]
            n = _words(res)
            hdr = HEADER_WORDS if has_header(res) else 0
            own = f" + buf{b}.w[i]" if write.rw else ""
            lines.append(f"    {{ uint lin = {xy}.y * {domain[0]}u + {xy}.x;")
            lines.append(f"      for (uint i = {hdr}u + lin; i < {n}u; i += {domain_expr})")
            lines.append(f"          buf{b}.w[i] = ({write.seed}u + {total}{own}) % {m}u;")
            if hdr:
                words = header_words(plan_size)
                stores = " ".join(f"buf{b}.w[{j}] = {wv}u;" for j, wv in enumerate(words))
                lines.append(f"      if (lin == 0u) {{ {stores} }}")
            lines.append("    }")
            return lines
        c = codec(res["format"])
        for mip, layer in write.subs:
            w, h = mip_extent(res, mip)
            b = by_access[(write.access, mip)]
            rel_layer = layer - a["subresource"]["layers"][0]
            coord = f"ivec3({xy}.x, {xy}.y, {rel_layer})"
            value = f"({write.seed}u + {total}) % {m}u" if m else "0u"
            if write.rw:
                own = _decode(c, f"imageLoad(img{b}, {coord})")
                value = f"({write.seed}u + {total} + {own}) % {m}u" if m else "0u"
            lines.append(f"    if ({xy}.x < {w}u && {xy}.y < {h}u) imageStore(img{b}, {coord}, {_encode(c, value)});")
        return lines

    version = ["#version 460", "#extension GL_EXT_ray_query : require"] if accels else ["#version 450"]
    header = [*version, '#include "probe/common.glsl"', *decls]
    if kind == "compute":
        body = []
        for r in probe.reads:
            body.append(f"        s += {read_expr(r.access, r.sub, 'compute', 'p')};")
        for b in accels:
            body += ray_query_lines(b, "        ")
        for w in probe.writes:
            body += ["    " + line for line in write_block(w, "s", "p", "stride_total")]
        src = "\n".join([
            *header,
            "layout(local_size_x = 8, local_size_y = 8) in;",
            "void main() {",
            "    uvec2 stride = gl_NumWorkGroups.xy * uvec2(8u, 8u);",
            f"    uint stride_total = {domain[0]}u * {domain[1]}u;",
            f"    for (uint y = gl_GlobalInvocationID.y; y < {domain[1]}u; y += stride.y)",
            f"    for (uint x = gl_GlobalInvocationID.x; x < {domain[0]}u; x += stride.x) {{",
            "        uvec2 p = uvec2(x, y);",
            "        uint s = 0u;",
            *body,
            "    }",
            "}",
        ]) + "\n"
        return ProbeShaders("compute", {"comp": src}, bindings, domain,
                            indirect_accesses=[i for i, a in enumerate(accesses) if a["usage"] == "indirect"])
    # raster
    vertex_accesses = [i for i, a in enumerate(accesses) if a["usage"] == "vertex"]
    vert_reads, frag_reads = [], []
    for r in probe.reads:
        if accesses[r.access]["usage"] == "vertex":
            continue
        stages = raster_read_stages(accesses[r.access]["stages"])
        if "vertex" in stages:
            vert_reads.append(f"    s += {read_expr(r.access, r.sub, 'vertex', 'p')};")
        if "fragment" in stages:
            frag_reads.append(f"    s += {read_expr(r.access, r.sub, 'fragment', 'p')};")
    for b in accels:  # ray queries in the stages the access declares (default: the fragment shader)
        stages = raster_read_stages(accesses[bindings[b].access]["stages"])
        if "vertex" in stages:
            vert_reads += ray_query_lines(b, "    ")
        if "fragment" in stages:
            frag_reads += ray_query_lines(b, "    ")
    # vertex attribute reads count once per stage too: they are read in the vertex stage only
    vert = "\n".join([
        *header,
        *(f"layout(location = {n}) in uint a{n};" for n in range(len(vertex_accesses))),
        "layout(location = 0) flat out uint v_sum;",
        "void main() {",
        "    gl_Position = vec4(probe_corner(uint(gl_VertexIndex)), 0.5, 1.0);",
        "    uint s = 0u;",
        *(f"    s += a{n};" for n in range(len(vertex_accesses))),
        *vert_reads,
        "    v_sum = s;",
        "}",
    ]) + "\n"
    color = [i for i, a in enumerate(accesses) if a["usage"] in ("color_attachment", "color_attachment_blend")]
    depth = next((i for i, a in enumerate(accesses) if a["usage"] in ("depth_attachment", "depth_read")), None)
    outs, stores = [], []
    for w in probe.writes:
        a = accesses[w.access]
        res = resources[a["resource"]]
        c = codec(res["format"]) if res["kind"] == "image" else None
        m = modulus(res)
        if a["usage"] in ("color_attachment", "color_attachment_blend"):
            loc = color.index(w.access)
            gtype = {"u": "uvec4", "i": "ivec4"}.get(_prefix(res), "vec4")
            outs.append(f"layout(location = {loc}) out {gtype} o{loc};")
            value = f"(({w.seed}u + s) % {m}u)" if m else "0u"
            stores.append(f"    o{loc} = {_encode(c, value)};")
        elif a["usage"] == "depth_attachment":
            value = f"(({w.seed}u + s) % {m}u)" if m else "0u"
            scale = c.scale if c else 0.0
            stores.append(f"    gl_FragDepth = float({value}) * {scale!r};")
        else:
            stores += write_block(w, "s", "p", f"{domain[0] * domain[1]}u")
    frag = "\n".join([
        *header,
        "layout(location = 0) flat in uint v_sum;",
        *outs,
        "void main() {",
        "    uvec2 p = uvec2(gl_FragCoord.xy);",
        "    uint s = v_sum;",
        *frag_reads,
        *stores,
        "}",
    ]) + "\n"
    return ProbeShaders(
        "raster", {"vert": vert, "frag": frag}, bindings, domain, color_accesses=color, depth_access=depth,
        vertex_accesses=vertex_accesses,
        index_accesses=[i for i, a in enumerate(accesses) if a["usage"] == "index"],
        indirect_accesses=[i for i, a in enumerate(accesses) if a["usage"] == "indirect"],
        layer_count=layer_count,
    )
