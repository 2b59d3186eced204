"""Pure-Python SPIR-V reflection, checked on real glslc output and against spirv-dis."""

from __future__ import annotations

import importlib.util
import re
import shutil
import struct
import subprocess
from pathlib import Path

import pytest
from locations import ROOT, TESTS

from rgraph.vk import spirv_grammar
from rgraph.vk.shaders import compile_shader
from rgraph.vk.spirv_reflect import SpirvError, _parse, reflect

ROOT = ROOT
SHADERS = TESTS / "shaders"
INCLUDE = [SHADERS / "include"]

pytestmark = pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RGRAPH_CACHE", str(tmp_path / "cache"))


def _compile_text(tmp_path: Path, name: str, text: str, **kwargs):
    path = tmp_path / name
    path.write_text(text)
    return compile_shader(path, **kwargs)


def _load_generator():
    spec = importlib.util.spec_from_file_location("gen_spirv_grammar", ROOT / "tools" / "gen_spirv_grammar.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ----------------------------------------------------------------------------- grammar


def test_grammar_module_is_up_to_date(tmp_path):
    generator = _load_generator()
    if generator.find_grammar() is None:
        pytest.skip("spirv-headers not installed (apt-get install spirv-headers)")
    out = tmp_path / "spirv_grammar.py"
    assert generator.main(["--output", str(out)]) == 0
    assert out.read_text() == (ROOT / "rgraph" / "vk" / "spirv_grammar.py").read_text(), (
        "rgraph/vk/spirv_grammar.py is stale: run .venv/bin/python tools/gen_spirv_grammar.py"
    )


def test_grammar_tables_hold_known_numbers():
    # Values fixed by the SPIR-V specification (they never change between revisions).
    assert spirv_grammar.MAGIC_NUMBER == 0x07230203
    assert spirv_grammar.OPCODES["OpDecorate"] == 71
    assert spirv_grammar.OPCODES["OpVariable"] == 59
    assert spirv_grammar.DECORATION["Binding"] == 33
    assert spirv_grammar.DECORATION["DescriptorSet"] == 34
    assert spirv_grammar.STORAGE_CLASS["PushConstant"] == 9
    assert spirv_grammar.EXECUTION_MODEL["RayGenerationKHR"] == spirv_grammar.EXECUTION_MODEL["RayGenerationNV"]


# ----------------------------------------------------------------------------- compute probe


def test_compute_probe_bindings():
    r = compile_shader(SHADERS / "probe.comp", include_dirs=INCLUDE).reflection
    assert (r.stage, r.entry_point, r.vk_stage) == ("comp", "main", "VK_SHADER_STAGE_COMPUTE_BIT")
    summary = [(b.set, b.binding, b.kind, b.count, b.name, b.writable, b.readable) for b in r.bindings]
    assert summary == [
        (0, 0, "storage_image", 1, "out_image", True, False),  # writeonly -> NonReadable
        (0, 1, "uniform_buffer", 1, "params", False, True),
        (1, 2, "storage_buffer", 1, "samples", False, True),  # readonly -> NonWritable members
        (1, 3, "storage_image", 1, "history", True, True),
    ]
    assert r.binding("out_image").image_format == "Rgba8"
    assert r.binding("history").image_format == "Rgba32f"
    assert r.binding("out_image").descriptor_type == "VK_DESCRIPTOR_TYPE_STORAGE_IMAGE"
    assert r.binding("params").block_bytes == 16 + 2 * 16 + 64  # std140 float[2] has stride 16
    assert r.binding("samples").block_bytes == 16  # the runtime array counts 0
    assert list(r.sets()) == [0, 1]


def test_compute_probe_push_constants_and_specialization():
    r = compile_shader(SHADERS / "probe.comp", include_dirs=INCLUDE).reflection
    # vec3 tint @0, float @12, mat4 @16, vec4[3] @80, float[2] @128 (stride 4), mat3 @144 (3 x 16)
    assert r.push_constant_bytes == 192
    assert r.local_size == (1, 8, 1)  # local_size_x_id defaults to 1
    assert r.local_size_spec_ids == (0, None, None)
    specs = [(s.spec_id, s.name, s.type, s.default, s.size) for s in r.spec_constants]
    assert specs == [
        (0, "", "uint", 1, 4),
        (1, "SCALE", "float", 2.5, 4),
        (2, "USE_TINT", "bool", True, 4),
        (3, "TAPS", "int", -3, 4),
    ]
    assert r.inputs == () and r.outputs == ()  # builtins are not stage variables


def test_literal_local_size_and_spirv_1_0_workgroup_size_builtin(tmp_path):
    text = "#version 450\nlayout(local_size_x = 8, local_size_y = 4) in;\nvoid main() {}\n"
    assert _compile_text(tmp_path, "lit.comp", text).reflection.local_size == (8, 4, 1)
    # SPIR-V 1.0 (Vulkan 1.0) expresses local_size_*_id as a BuiltIn WorkgroupSize spec composite.
    spec = "#version 450\nlayout(local_size_x_id = 3, local_size_y = 2) in;\n" \
           "layout(constant_id = 3) const uint X = 64;\nvoid main() {}\n"
    path = tmp_path / "old.comp"
    path.write_text(spec)
    out = tmp_path / "old.spv"
    subprocess.run(["glslc", "--target-env=vulkan1.0", "-o", str(out), str(path)], check=True)
    r = reflect(out.read_bytes())
    assert r.spirv_version == (1, 0)
    # the spec ids can only come from the WorkgroupSize composite (OpExecutionMode LocalSize is 1 2 1)
    assert (r.local_size, r.local_size_spec_ids) == ((1, 2, 1), (3, None, None))


# ----------------------------------------------------------------------------- raster pair


def test_vertex_inputs_and_outputs():
    r = compile_shader(SHADERS / "raster.vert").reflection
    assert r.stage == "vert"
    inputs = [(v.location, v.name, v.type, v.vk_format) for v in r.inputs]
    assert inputs == [
        (0, "position", "vec3", "VK_FORMAT_R32G32B32_SFLOAT"),
        (1, "uv", "vec2", "VK_FORMAT_R32G32_SFLOAT"),
        (2, "joints", "uvec4", "VK_FORMAT_R32G32B32A32_UINT"),
        (3, "skew", "mat2", None),
    ]
    assert r.inputs[3].columns == 2
    assert [(v.location, v.name, v.type) for v in r.outputs] == [
        (0, "v_uv", "vec2"), (1, "v_material", "uint"), (2, "v_normal", "vec3")]  # gl_Position excluded
    assert [(b.binding, b.kind, b.block_bytes) for b in r.bindings] == [(0, "uniform_buffer", 64)]


def test_fragment_samplers_and_outputs():
    r = compile_shader(SHADERS / "raster.frag").reflection
    assert [(b.set, b.binding, b.kind, b.count, b.name) for b in r.bindings] == [
        (0, 1, "combined_image_sampler", 4, "textures"),
        (0, 2, "sampled_image", 1, "shadow_map"),
        (0, 3, "sampler", 1, "shadow_sampler"),
        (1, 0, "input_attachment", 1, "gbuffer"),
    ]
    assert r.binding("gbuffer").input_attachment_index == 0
    assert not any(b.writable for b in r.bindings)
    assert [(v.location, v.name, v.vk_format) for v in r.outputs] == [
        (0, "color", "VK_FORMAT_R32G32B32A32_SFLOAT"),
        (1, "ids", "VK_FORMAT_R32G32_UINT"),
        (3, "depth_out", "VK_FORMAT_R32_SFLOAT"),
    ]
    assert [v.location for v in r.inputs] == [0, 1, 2]


def test_descriptor_arrays_texel_buffers_and_ray_tracing(tmp_path):
    frag = """#version 460
#extension GL_EXT_nonuniform_qualifier : require
layout(set = 0, binding = 0) uniform sampler2D grid[6];
layout(set = 0, binding = 1) uniform sampler2D bindless[];
layout(set = 0, binding = 2) uniform samplerBuffer lut;
layout(set = 0, binding = 3, r32f) uniform writeonly imageBuffer log_out;
layout(location = 0) flat in int idx;
layout(location = 0) out vec4 color;
void main() {
    color = texture(grid[5], vec2(0)) + texture(bindless[nonuniformEXT(idx)], vec2(0)) + texelFetch(lut, idx);
    imageStore(log_out, idx, color);
}
"""
    r = _compile_text(tmp_path, "arrays.frag", frag).reflection
    assert [(b.binding, b.kind, b.count, b.writable) for b in r.bindings] == [
        (0, "combined_image_sampler", 6, False),
        (1, "combined_image_sampler", 0, False),  # runtime-sized
        (2, "uniform_texel_buffer", 1, False),
        (3, "storage_texel_buffer", 1, True),
    ]
    rgen = """#version 460
#extension GL_EXT_ray_tracing : require
layout(set = 0, binding = 0) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = 1, rgba16f) uniform image2D target;
layout(location = 0) rayPayloadEXT vec4 payload;
void main() {
    traceRayEXT(tlas, gl_RayFlagsOpaqueEXT, 0xff, 0, 0, 0, vec3(0), 0.0, vec3(0, 0, 1), 100.0, 0);
    imageStore(target, ivec2(gl_LaunchIDEXT.xy), payload);
}
"""
    r = _compile_text(tmp_path, "trace.rgen", rgen).reflection
    assert (r.stage, r.vk_stage, r.local_size) == ("rgen", "VK_SHADER_STAGE_RAYGEN_BIT_KHR", None)
    assert [(b.binding, b.kind, b.name) for b in r.bindings] == [
        (0, "acceleration_structure", "tlas"), (1, "storage_image", "target")]
    assert r.outputs == () and r.inputs == ()  # the payload is not a stage output


def test_interface_block_members_get_consecutive_locations(tmp_path):
    vert = """#version 460
layout(location = 2) out Varyings { vec3 normal; dvec4 wide; float depth; } v;
void main() { v.normal = vec3(1); v.wide = dvec4(0); v.depth = 1.0; gl_Position = vec4(0); }
"""
    r = _compile_text(tmp_path, "block.vert", vert).reflection
    assert [(v.location, v.name, v.type) for v in r.outputs] == [
        (2, "v.normal", "vec3"), (3, "v.wide", "dvec4"), (5, "v.depth", "float")]


# ----------------------------------------------------------------------------- cross-check with spirv-dis


@pytest.mark.skipif(shutil.which("spirv-dis") is None, reason="spirv-tools not installed")
@pytest.mark.parametrize("name", ["probe.comp", "raster.vert", "raster.frag"])
def test_decorations_match_spirv_dis(name):
    spirv = compile_shader(SHADERS / name, include_dirs=INCLUDE).spirv
    listing = subprocess.run(["spirv-dis", "--raw-id", "-"], input=spirv, capture_output=True,
                             check=True).stdout.decode()
    module = _parse(spirv)
    decoration_names = {v: k for k, v in reversed(spirv_grammar.DECORATION.items())}
    ours = {(target, decoration_names[d], tuple(args)) for target, decos in module.decorations.items()
            for d, args in decos.items() if d != spirv_grammar.DECORATION["BuiltIn"]}
    ours |= {(key, decoration_names[d], tuple(args)) for key, decos in module.member_decorations.items()
             for d, args in decos.items() if d != spirv_grammar.DECORATION["BuiltIn"]}
    theirs = set()
    for line in listing.splitlines():
        if m := re.match(r"\s*OpDecorate %(\d+) (\w+)((?: \d+)*)\s*$", line):
            theirs.add((int(m[1]), m[2], tuple(int(x) for x in m[3].split())))
        elif m := re.match(r"\s*OpMemberDecorate %(\d+) (\d+) (\w+)((?: \d+)*)\s*$", line):
            theirs.add(((int(m[1]), int(m[2])), m[3], tuple(int(x) for x in m[4].split())))
    assert theirs, "parsed nothing from spirv-dis"
    assert ours == theirs
    # spec constant defaults as spirv-dis prints them
    for m in re.finditer(r"%(\d+) = OpSpecConstant %\d+ (-?[\d.]+)", listing):
        value = module.constants[int(m[1])][1]
        assert value == (float(m[2]) if "." in m[2] else int(m[2]))


# ----------------------------------------------------------------------------- bad input


def test_rejects_non_spirv_and_truncated_modules():
    with pytest.raises(SpirvError, match="magic"):
        reflect(b"\0" * 32)
    with pytest.raises(SpirvError):
        reflect(b"\x03\x02")
    spirv = compile_shader(SHADERS / "raster.vert").spirv
    ten_word_capability = struct.pack("<I", (10 << 16) | spirv_grammar.OPCODES["OpCapability"])
    with pytest.raises(SpirvError, match="truncated"):
        reflect(spirv[:20] + ten_word_capability + b"\1\0\0\0")


def test_big_endian_module_reflects_the_same():
    spirv = compile_shader(SHADERS / "raster.frag").spirv
    swapped = b"".join(spirv[i : i + 4][::-1] for i in range(0, len(spirv), 4))
    assert reflect(swapped) == reflect(spirv)


def test_mesh_and_geometry_stages(tmp_path):
    mesh = """#version 460
#extension GL_EXT_mesh_shader : require
layout(local_size_x = 32) in;
layout(triangles, max_vertices = 3, max_primitives = 1) out;
layout(location = 0) out vec3 colour[];
void main() {
    SetMeshOutputsEXT(3, 1);
    gl_MeshVerticesEXT[gl_LocalInvocationIndex % 3].gl_Position = vec4(0);
    colour[gl_LocalInvocationIndex % 3] = vec3(1);
    gl_PrimitiveTriangleIndicesEXT[0] = uvec3(0, 1, 2);
}
"""
    r = _compile_text(tmp_path, "tri.mesh", mesh).reflection
    assert (r.stage, r.vk_stage, r.local_size) == ("mesh", "VK_SHADER_STAGE_MESH_BIT_EXT", (32, 1, 1))
    assert [(v.location, v.name, v.type) for v in r.outputs] == [(0, "colour", "vec3")]  # per-vertex array
    geom = """#version 460
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
layout(location = 0) in vec2 v_uv[];
layout(location = 0) out vec2 g_uv;
void main() {
    for (int i = 0; i < 3; ++i) { g_uv = v_uv[i]; gl_Position = gl_in[i].gl_Position; EmitVertex(); }
}
"""
    r = _compile_text(tmp_path, "pass.geom", geom).reflection
    assert [(v.location, v.name, v.type) for v in r.inputs] == [(0, "v_uv", "vec2")]
    assert [(v.location, v.name, v.type) for v in r.outputs] == [(0, "g_uv", "vec2")]
