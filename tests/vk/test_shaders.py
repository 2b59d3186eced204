"""glslc compilation: stages, defines, the content-hash cache, errors, shader directories."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from locations import ROOT, TESTS

from rgraph.errors import RGraphError
from rgraph.vk import shaders
from rgraph.vk.shaders import compile_shader, find_shader, shader_dirs, stage_of

ROOT = ROOT
SHADERS = TESTS / "shaders"

needs_glslc = pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")

COMPUTE = """#version 460
#include "local.h"
layout(local_size_x = LOCAL_X) in;
layout(set = 0, binding = 0) buffer Out { uint v[]; } out_buf;
void main() { out_buf.v[gl_GlobalInvocationID.x] = VALUE; }
"""
HEADER = "#ifndef LOCAL_X\n#define LOCAL_X 4\n#endif\n"


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RGRAPH_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("RGRAPH_SHADER_PATH", raising=False)


@pytest.fixture
def project(tmp_path):
    """A shader that includes a header from an include directory."""
    src = tmp_path / "src"
    inc = tmp_path / "inc"
    src.mkdir()
    inc.mkdir()
    (src / "fill.comp").write_text(COMPUTE)
    (inc / "local.h").write_text(HEADER)
    return src / "fill.comp", inc


@pytest.fixture
def glslc_calls(monkeypatch):
    """Compile invocations of glslc (the version probe is not counted)."""
    calls: list[list[str]] = []
    real = shaders.run_glslc

    def counting(args, cwd=None):
        if "-MD" in args:
            calls.append(list(args))
        return real(args, cwd=cwd)

    monkeypatch.setattr(shaders, "run_glslc", counting)
    return calls


# ----------------------------------------------------------------------------- stages and defines


def test_stage_from_extension():
    assert stage_of(Path("a/b.comp")) == "comp"
    assert stage_of(Path("blur.frag.glsl")) == "frag"
    assert stage_of(Path("hit.rchit")) == "rchit"
    assert stage_of(Path("mesh.mesh")) == "mesh"
    assert stage_of(Path("common.glsl")) is None
    assert stage_of(Path("README")) is None


@needs_glslc
def test_explicit_stage_for_plain_glsl(tmp_path):
    path = tmp_path / "tri.glsl"
    path.write_text("#version 460\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec4(1); }\n")
    with pytest.raises(RGraphError, match="unknown shader stage"):
        compile_shader(path)
    shader = compile_shader(path, stage="frag")
    assert (shader.stage, shader.reflection.stage) == ("frag", "frag")
    assert shader.spirv[:4] == b"\x03\x02\x23\x07"


@needs_glslc
def test_defines_specialize_one_source(project):
    path, inc = project
    four = compile_shader(path, include_dirs=[inc], defines={"VALUE": 7})
    wide = compile_shader(path, include_dirs=[inc], defines={"VALUE": 7, "LOCAL_X": 64})
    assert (four.reflection.local_size, wide.reflection.local_size) == ((4, 1, 1), (64, 1, 1))
    assert four.defines == (("VALUE", "7"),)
    assert wide.key != four.key and wide.spirv != four.spirv
    flags = compile_shader(path, include_dirs=[inc], defines={"VALUE": True}).defines
    assert flags == (("VALUE", "1"),)
    with pytest.raises(RGraphError, match="bad macro name"):
        compile_shader(path, include_dirs=[inc], defines={"2BAD": 1})
    with pytest.raises(RGraphError, match="finite"):
        compile_shader(path, include_dirs=[inc], defines={"VALUE": float("nan")})


@needs_glslc
def test_sss_sample_count_define_changes_the_code():
    low = compile_shader(SHADERS / "probe.comp", include_dirs=[SHADERS / "include"], defines={"SSS_SAMPLES": 2})
    high = compile_shader(SHADERS / "probe.comp", include_dirs=[SHADERS / "include"],
                          defines={"SSS_SAMPLES": 16})
    assert low.spirv != high.spirv
    assert low.reflection.bindings == high.reflection.bindings  # same interface, different body


# ----------------------------------------------------------------------------- cache


@needs_glslc
def test_cache_hit_skips_glslc_and_header_edit_recompiles(project, glslc_calls, tmp_path):
    path, inc = project
    cache = tmp_path / "c"
    first = compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    assert len(glslc_calls) == 1
    again = compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    assert len(glslc_calls) == 1, "unchanged shader must come from the cache"
    assert (again.spirv, again.key) == (first.spirv, first.key)
    assert again.reflection == first.reflection

    compile_shader(path, include_dirs=[inc], defines={"VALUE": 2}, cache=cache)  # other defines
    assert len(glslc_calls) == 2

    (inc / "local.h").write_text("#define LOCAL_X 16\n")  # edit the included header
    edited = compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    assert len(glslc_calls) == 3
    assert edited.reflection.local_size == (16, 1, 1)

    (inc / "local.h").write_text(HEADER)  # back: the first result is still cached
    back = compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    assert len(glslc_calls) == 3 and back.spirv == first.spirv

    path.write_text(COMPUTE.replace("VALUE;", "VALUE + 1u;"))  # edit the source
    compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    assert len(glslc_calls) == 4


@needs_glslc
def test_real_recompile_after_touching_an_include(project, tmp_path):
    path, inc = project
    cache = tmp_path / "c"
    before = compile_shader(path, include_dirs=[inc], defines={"VALUE": 3}, cache=cache)
    header = inc / "local.h"
    header.write_text("#define LOCAL_X 32\n")
    after = compile_shader(path, include_dirs=[inc], defines={"VALUE": 3}, cache=cache)
    assert before.reflection.local_size == (4, 1, 1)
    assert after.reflection.local_size == (32, 1, 1)
    spv_files = sorted(cache.glob("*.spv"))
    assert len(spv_files) == 2 and len(list(cache.glob("*.json"))) == 1
    # the cache file is the real glslc output for this key
    assert (cache / f"{after.key}.spv").read_bytes() == after.spirv


@needs_glslc
def test_default_cache_dir_honours_rgraph_cache(project, tmp_path):
    path, inc = project
    shader = compile_shader(path, include_dirs=[inc], defines={"VALUE": 5})
    assert shaders.cache_dir() == tmp_path / "cache" / "spirv"
    assert (tmp_path / "cache" / "spirv" / f"{shader.key}.spv").is_file()


@needs_glslc
def test_unwritable_cache_compiles_to_memory(project, tmp_path, glslc_calls):
    path, inc = project
    blocker = tmp_path / "not-a-dir"
    blocker.write_text("a file where the cache directory should be")
    shader = compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=blocker / "spirv")
    assert shader.reflection.local_size == (4, 1, 1)
    compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=blocker / "spirv")
    assert len(glslc_calls) == 2  # nothing could be stored, so nothing is served


@needs_glslc
def test_read_only_cache_still_serves_hits(project, tmp_path, glslc_calls, monkeypatch):
    path, inc = project
    cache = tmp_path / "shared"
    compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)

    def refuse(*_args):
        raise PermissionError("read-only file system")

    monkeypatch.setattr(shaders, "_write_atomic", refuse)  # root ignores chmod, so simulate EROFS
    compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    assert len(glslc_calls) == 1
    compile_shader(path, include_dirs=[inc], defines={"VALUE": 9}, cache=cache)  # miss: compiles, no store
    assert len(glslc_calls) == 2
    assert len(list(cache.glob("*.spv"))) == 1


@needs_glslc
def test_corrupt_cache_entry_is_recompiled(project, tmp_path, glslc_calls):
    path, inc = project
    cache = tmp_path / "c"
    good = compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    (cache / f"{good.key}.spv").write_bytes(b"junk")
    again = compile_shader(path, include_dirs=[inc], defines={"VALUE": 1}, cache=cache)
    assert len(glslc_calls) == 2 and again.spirv == good.spirv


# ----------------------------------------------------------------------------- errors


@needs_glslc
def test_syntax_error_points_at_glsl_file_line_col():
    with pytest.raises(RGraphError) as info:
        compile_shader(SHADERS / "broken.comp")
    diag = info.value.first
    assert diag.location.file == str(SHADERS / "broken.comp")
    assert (diag.location.line, diag.location.col) == (5, 15)
    assert "undeclared identifier" in diag.message
    assert str(info.value).startswith(f"{SHADERS / 'broken.comp'}:5:15: error: ")


@needs_glslc
def test_error_in_header_points_at_the_header(project):
    path, inc = project
    (inc / "local.h").write_text("#define LOCAL_X 4\nint broken = ;\n")
    with pytest.raises(RGraphError) as info:
        compile_shader(path, include_dirs=[inc], defines={"VALUE": 1})
    assert info.value.first.location.file == str(inc / "local.h")
    assert info.value.first.location.line == 2
    assert "VALUE=1" in info.value.first.message  # the define variant that failed


@needs_glslc
def test_every_error_becomes_a_diagnostic(tmp_path):
    path = tmp_path / "two.comp"
    path.write_text("#version 460\nlayout(local_size_x = 1) in;\nvoid main() {\n  a = 1;\n  b = 2;\n}\n")
    with pytest.raises(RGraphError) as info:
        compile_shader(path)
    assert [(d.location.line, d.location.col) for d in info.value.diagnostics] == [(4, 3), (5, 3)]


def test_missing_glslc_says_what_to_install(tmp_path, monkeypatch):
    path = tmp_path / "x.comp"
    path.write_text("#version 460\nvoid main() {}\n")
    monkeypatch.setenv("RGRAPH_GLSLC", str(tmp_path / "no-such-glslc"))
    with pytest.raises(RGraphError, match="apt-get install glslc") as info:
        compile_shader(path)
    assert info.value.first.location.file == str(path)


def test_missing_shader_file(tmp_path):
    with pytest.raises(RGraphError, match="not found"):
        compile_shader(tmp_path / "absent.comp")


def test_parse_depfile_handles_continuations_and_escaped_spaces(tmp_path):
    text = "out.spv: /a/main.comp \\\n  /a/my\\ dir/x.h rel.h\n"
    assert shaders._parse_depfile(text, tmp_path) == [
        Path("/a/main.comp"), Path("/a/my dir/x.h"), (tmp_path / "rel.h").resolve()]


# ----------------------------------------------------------------------------- shader directories


def test_shader_dirs_finds_the_checkout_shaders_dir():
    assert shader_dirs()[-1] == ROOT / "shaders"


def test_shader_dirs_without_installing_rgraph(tmp_path):
    """A plain checkout on PYTHONPATH (python -S: no site-packages, no editable finder)."""
    code = "import rgraph.vk.shaders as s; print(s.shader_dirs()[-1])"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-S", "-c", code], env=env, cwd=tmp_path, capture_output=True,
                         text=True, check=True).stdout.strip()
    assert Path(out) == ROOT / "shaders"


def test_find_shader_searches_user_dirs_first(tmp_path, monkeypatch):
    user = tmp_path / "mine"
    (user / "fx").mkdir(parents=True)
    (user / "fx" / "glow.comp").write_text("// user shader\n")
    monkeypatch.setenv("RGRAPH_SHADER_PATH", str(user))
    assert shader_dirs()[0] == user
    assert find_shader("fx/glow.comp") == user / "fx" / "glow.comp"
    with pytest.raises(RGraphError, match="not found"):
        find_shader("fx/missing.comp")


@needs_glslc
def test_bundled_shader_dirs_are_include_paths(tmp_path, monkeypatch):
    lib = tmp_path / "lib"
    (lib / "common").mkdir(parents=True)
    (lib / "common" / "consts.glsl").write_text("const uint MAGIC = 42u;\n")
    monkeypatch.setenv("RGRAPH_SHADER_PATH", str(lib))
    user = tmp_path / "user.comp"
    user.write_text('#version 460\n#include "common/consts.glsl"\nlayout(local_size_x = 1) in;\n'
                    "layout(binding = 0) buffer B { uint v; } b;\nvoid main() { b.v = MAGIC; }\n")
    assert compile_shader(user).reflection.bindings[0].kind == "storage_buffer"
