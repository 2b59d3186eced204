"""One test per class of bad input: exact FILE:LINE:COL, message, exit 2, no traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from rgraph.cli import main

HEADER = "rgraph: 1\n"
IMG = "  a: {kind: image, format: r8g8b8a8_unorm}\n"

CASES: list[tuple[str, bytes | str, tuple[int, int], str]] = [
    ("unknown_key", HEADER + "pases: {}\n", (2, 1), "unknown key 'pases' in the file; did you mean 'passes'?"),
    ("wrong_version", "rgraph: 2\n", (1, 9), "unsupported format version 2"),
    ("missing_version", "name: x\n", (1, 1), "missing required key 'rgraph'"),
    ("top_level_list", "- a\n- b\n", (1, 1), "must be a mapping"),
    ("empty_file", "", (1, 1), "but this is empty"),
    ("yaml_syntax", HEADER + "resources: [\n", (3, 1), "YAML syntax error"),
    ("duplicate_key", HEADER + "resources:\n" + IMG + IMG, (4, 3), "duplicate key 'a' (first defined at line 3)"),
    ("object_tag", HEADER + "resources: {a: !!python/object:os.system {}}\n", (2, 16), "YAML tag '!!python/object:os.system' is not allowed"),
    ("custom_tag", HEADER + "name: !env HOME\n", (2, 7), "YAML tag '!env' is not allowed"),
    ("non_utf8", b"rgraph: 1\nname: \"\xff\"\n", (2, 8), "not valid UTF-8"),
    ("unknown_resource_kind", HEADER + "resources:\n  a: {kind: imag, format: d32_sfloat}\n", (3, 13), "unknown resource kind 'imag'; did you mean 'image'?"),
    ("unknown_format", HEADER + "resources:\n  a: {kind: image, format: d32_sfloa}\n", (3, 28), "unknown format 'd32_sfloa'; did you mean 'd32_sfloat'?"),
    ("unknown_usage", HEADER + "resources:\n" + IMG + "passes:\n  p: {kind: raster, reads: {a: smapled}}\n", (5, 32), "unknown usage 'smapled'; did you mean 'sampled'?"),
    ("unknown_pass_kind", HEADER + "passes:\n  p: {kind: rastr}\n", (3, 13), "unknown pass kind 'rastr'; did you mean 'raster'?"),
    ("unknown_feature", HEADER + "passes:\n  p: {kind: raster, requires: [shadow_light]}\n", (3, 32), "did you mean 'shadow_lights'?"),
    ("missing_kind", HEADER + "passes:\n  p: {reads: {}}\n", (3, 3), "missing required key 'kind' in pass 'p'"),
    ("wrong_type", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, mips: 1.5}\n", (3, 50), "expected an integer or a '${...}' expression for 'mips', got number 1.5"),
    ("undefined_resource", HEADER + "resources:\n" + IMG + "passes:\n  p: {kind: raster, reads: {b: sampled}}\n", (5, 29), "reads undefined resource 'b'"),
    ("undefined_output", HEADER + "outputs: [x]\n", (2, 11), "output 'x' is not a resource"),
    ("read_before_write", HEADER + "resources:\n" + IMG + "passes:\n  p: {kind: raster, reads: {a: sampled}}\n", (5, 32), "reads 'a' before any pass writes it"),
    ("usage_format_mismatch", HEADER + "resources:\n  a: {kind: image, format: d32_sfloat}\npasses:\n  p: {kind: raster, writes: {a: color_attachment}}\n", (5, 33), "format d32_sfloat does not support usage 'color_attachment'"),
    ("storage_on_srgb", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_srgb}\npasses:\n  p: {kind: compute, writes: {a: storage_write}}\n", (5, 34), "does not support usage 'storage_write'"),
    ("usage_resource_kind", HEADER + "resources:\n  b: {kind: buffer, bytes: 64}\npasses:\n  p: {kind: raster, writes: {b: color_attachment}}\n", (5, 33), "needs an image"),
    ("usage_pass_kind", HEADER + "resources:\n" + IMG + "passes:\n  p: {kind: compute, writes: {a: color_attachment}}\n", (5, 34), "not possible in a compute pass"),
    ("write_under_reads", HEADER + "resources:\n" + IMG + "passes:\n  p: {kind: compute, reads: {a: storage_rw}}\n", (5, 33), "list it under 'writes'"),
    ("negative_size", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, size: [-4, 5]}\n", (3, 51), "image width -4 is out of range"),
    ("absurd_size", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, size: [65536, 5]}\n", (3, 51), "maxImageDimension2D"),
    ("absurd_layers", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, layers: 100000}\n", (3, 52), "maxImageArrayLayers"),
    ("absurd_buffer", HEADER + "resources:\n  a: {kind: buffer, bytes: 99999999999999}\n", (3, 28), "out of range"),
    ("bad_samples", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, samples: 3}\n", (3, 53), "samples must be one of"),
    ("undefined_param", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, layers: \"${params.x}\"}\n", (3, 55), "unknown name 'params.x'"),
    ("expr_division_by_zero", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, layers: \"${1/0}\"}\n", (3, 56), "division by zero"),
    ("expr_syntax", HEADER + "params: {n: 2}\nresources:\n  a: {kind: image, format: r8g8b8a8_unorm, layers: \"${params.n +* 2}\"}\n", (4, 65), "found '*'"),
    ("bad_selector", HEADER + "resources:\n" + IMG + "passes:\n  p: {kind: compute, writes: {\"a[layr=0]\": storage_write}}\n", (5, 31), "bad subresource selector"),
    ("selector_out_of_range", HEADER + "resources:\n  a: {kind: image, format: r8g8b8a8_unorm, layers: 4}\npasses:\n  p: {kind: compute, writes: {\"a[layer=2:9]\": storage_write}}\n", (5, 31), "layer range 2:9 is outside 'a'"),
    ("missing_include", HEADER + "include: [nope.yaml]\n", (2, 11), "included file 'nope.yaml' not found"),
    ("self_include", HEADER + "include: [bad.yaml]\n", (2, 11), "include cycle"),
    ("queue_kind", HEADER + "passes:\n  p: {kind: raster, queue: compute}\n", (3, 28), "cannot run on the compute queue"),
    ("unknown_long_form_key", HEADER + "resources:\n" + IMG + "passes:\n  p: {kind: raster, writes: {a: {usage: color_attachment, stagez: [vertex]}}}\n", (5, 33), "unknown key 'stagez'"),
    ("twice_in_pass", HEADER + "resources:\n" + IMG + "passes:\n  w: {kind: compute, writes: {a: storage_write}}\n  p: {kind: compute, reads: {a: sampled}, writes: {a: storage_write}}\n", (6, 55), "uses overlapping parts of 'a'"),
]


@pytest.mark.parametrize("name,text,where,message", CASES, ids=[c[0] for c in CASES])
def test_error_location(tmp_path: Path, capsys, name, text, where, message) -> None:
    path = tmp_path / "bad.yaml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    code = main(["validate", str(path)])
    err = capsys.readouterr().err
    assert code == 2
    first = err.splitlines()[0]
    assert first.startswith(f"{path}:{where[0]}:{where[1]}: error: "), first
    assert message in first
    assert "Traceback" not in err


def test_include_cycle_between_two_files(tmp_path: Path, capsys) -> None:
    (tmp_path / "a.yaml").write_text("rgraph: 1\ninclude: [b.yaml]\n")
    (tmp_path / "b.yaml").write_text("rgraph: 1\n\ninclude: [a.yaml]\n")
    assert main(["validate", str(tmp_path / "a.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{tmp_path / 'b.yaml'}:3:11: error: include cycle: a.yaml -> b.yaml -> a.yaml")


def test_duplicate_name_across_include(tmp_path: Path, capsys) -> None:
    (tmp_path / "a.yaml").write_text("rgraph: 1\ninclude: [b.yaml]\nresources:\n" + IMG)
    (tmp_path / "b.yaml").write_text("rgraph: 1\nresources:\n" + IMG)
    assert main(["validate", str(tmp_path / "a.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{tmp_path / 'b.yaml'}:3:3: error: duplicate resource 'a'")


def test_unknown_param_override(tmp_path: Path, capsys) -> None:
    (tmp_path / "g.yaml").write_text("rgraph: 1\nparams: {hbao.steps: 4}\n")
    assert main(["validate", str(tmp_path / "g.yaml"), "-p", "hbao.stepz=3"]) == 2
    assert "unknown param 'hbao.stepz'; did you mean 'hbao.steps'?" in capsys.readouterr().err


def test_missing_file(capsys) -> None:
    assert main(["validate", "does/not/exist.yaml"]) == 2
    assert capsys.readouterr().err.startswith("does/not/exist.yaml:1:1: error: no such file")


def test_scene_errors_are_located(tmp_path: Path, capsys) -> None:
    (tmp_path / "g.yaml").write_text("rgraph: 1\n")
    (tmp_path / "s.yaml").write_text("scene: 1\nmaterials: {skin: {roughness: 0.5}}\nmeshes:\n  - {shape: box, material: skni}\n")
    assert main(["validate", str(tmp_path / "g.yaml"), "--scene", str(tmp_path / "s.yaml")]) == 2
    assert "s.yaml:4:28: error: unknown material 'skni'; did you mean 'skin'?" in capsys.readouterr().err


def test_cli_subprocess_prints_no_traceback(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("rgraph: 1\nresources: {a: {kind: image, format: nope}}\n")
    proc = subprocess.run([sys.executable, "-m", "rgraph", "compile", str(path)], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert f"{path}:2:38: error: unknown format 'nope'" in proc.stderr
