"""Hostile graph and scene files (issue 14): each gets one located error line, exit 2, quickly."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from rgraph.cli import main

HUGE = "9" * 5000


def _validate(tmp_path: Path, capsys, text: str | bytes, *extra: str) -> tuple[int, str]:
    path = tmp_path / "g.yaml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8", "surrogatepass"))
    code = main(["validate", str(path), *extra])
    return code, capsys.readouterr().err


CASES = [
    ("huge_int", f"rgraph: 1\nparams: {{a: {HUGE}}}\n", (2, 13), "integer out of range"),
    ("huge_hex", "rgraph: 1\nparams: {a: 0x" + "f" * 40 + "}\n", (2, 13), "integer out of range"),
    ("huge_in_expression", 'rgraph: 1\nresources: {b: {kind: buffer, bytes: "${' + "9" * 40 + '}"}}\n', (2, 41),
     "value out of range"),
    ("flow_depth", "rgraph: 1\nx: " + "[" * 100_000 + "]" * 100_000 + "\n", (2, 68), "nested deeper than 64"),
    ("map_depth", "rgraph: 1\nx: " + "{a: " * 3000 + "1" + "}" * 3000 + "\n", (2, 260), "nested deeper than 64"),
    ("block_depth", "rgraph: 1\nx:\n" + "".join(" " * i + "-\n" for i in range(200)), (66, 64), "nested deeper than 64"),
    ("recursive_alias", "rgraph: 1\nparams: &a {x: *a}\n", (2, 16), "recursive alias '*a'"),
    ("undefined_alias", "rgraph: 1\nparams: {x: *a}\n", (2, 13), "undefined alias '*a'"),
    ("float_tag", "rgraph: 1\nparams: {a: !!float abc}\n", (2, 13), "YAML tag '!!float' is not allowed"),
    ("int_tag", "rgraph: 1\nparams: {a: !!int 0x_}\n", (2, 13), "YAML tag '!!int' is not allowed"),
    ("int_tag_text", "rgraph: 1\nparams: {a: !!int abc}\n", (2, 13), "YAML tag '!!int' is not allowed"),
    ("bool_tag", "rgraph: 1\nparams: {a: !!bool maybe}\n", (2, 13), "YAML tag '!!bool' is not allowed"),
    ("yaml_1_1", "%YAML 1.1\n---\nrgraph: 1\nparams: {a: 1:30, b: yes}\n", (2, 1), "'%YAML 1.1' is not supported"),
    ("tag_directive", "%TAG !e! tag:example.com,2000:\n---\nrgraph: 1\n", (2, 1), "'%TAG' directives"),
    ("lone_surrogate", 'rgraph: 1\nname: "\\ud800"\n', (2, 7), "lone surrogate"),
    ("escape_in_name", 'rgraph: 1\nname: "\\e[31mred"\n', (2, 7), "control character U+001B"),
    ("raw_control", b"rgraph: 1\nname: a\x01b\n", (2, 8), "control character U+0001"),
    ("memory_policy", 'rgraph: 1\nmemory_policy: "blocks:0"\n', (2, 16), "unknown block size in policy 'blocks:0'"),
    ("nul_include", 'rgraph: 1\ninclude: ["a\\0b.yaml"]\n', (2, 11), "control character U+0000"),
    ("long_include", "rgraph: 1\ninclude: [" + "x" * 300 + ".yaml]\n", (2, 11), "a component of 305 bytes"),
    ("outside_include", "rgraph: 1\ninclude: [../x.yaml]\n", (2, 11), "lies outside the graph's folder"),
    ("absolute_include", "rgraph: 1\ninclude: [/etc/passwd]\n", (2, 11), "lies outside the graph's folder"),
    ("outside_scene", "rgraph: 1\nscene: ../s.yaml\n", (2, 8), "lies outside the graph's folder"),
    ("pass_key", "rgraph: 1\npasses: {p: {kind: raster, writez: {}}}\n", (2, 28),
     "unknown key 'writez' in pass 'p'; did you mean 'writes'? (valid keys: "),
    ("resource_key", "rgraph: 1\nresources: {a: {kind: image, format: r8_unorm, size: output, layerz: 2}}\n", (2, 62),
     "did you mean 'layers'? (valid keys: kind, format, size, layers"),
]


@pytest.mark.parametrize("name,text,where,message", CASES, ids=[c[0] for c in CASES])
def test_hostile_graph(tmp_path: Path, capsys, name, text, where, message) -> None:
    began = time.perf_counter()
    code, err = _validate(tmp_path, capsys, text)
    assert time.perf_counter() - began < 10
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1, err[:500]
    assert lines[0].startswith(f"{tmp_path / 'g.yaml'}:{where[0]}:{where[1]}: error: "), lines[0][:300]
    assert message in lines[0], lines[0][:300]


def test_echoed_values_are_escaped_and_cut(tmp_path: Path, capsys) -> None:
    code, err = _validate(tmp_path, capsys, 'rgraph: 1\nresources: {a: {kind: image, format: "r8 '
                          + "x" * 500 + '", size: output}}\n')
    assert code == 2 and len(err.splitlines()) == 1
    assert "(503 characters)" in err and len(err) < 400


def test_alias_bomb_is_refused_while_composing(tmp_path: Path, capsys) -> None:
    lines = ["rgraph: 1", "a0: &a0 [" + ",".join(["x"] * 10) + "]"]
    lines += [f"a{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * 10) + "]" for i in range(1, 9)]
    began = time.perf_counter()
    code, err = _validate(tmp_path, capsys, "\n".join(lines) + "\n")
    assert code == 2 and "aliases expand to more than 100,000 values" in err
    assert time.perf_counter() - began < 5


def test_include_fan_out_includes_each_file_once(tmp_path: Path, capsys) -> None:
    for i in range(30):
        (tmp_path / f"f{i}.yaml").write_text(f"rgraph: 1\ninclude: [f{i + 1}.yaml, f{i + 1}.yaml]\n")
    (tmp_path / "f30.yaml").write_text("rgraph: 1\nparams: {deep: 1}\n")
    began = time.perf_counter()
    code, err = _validate(tmp_path, capsys, "rgraph: 1\ninclude: [f0.yaml]\n")
    assert code == 0, err
    assert time.perf_counter() - began < 5


def test_error_in_included_file_names_the_include_site(tmp_path: Path, capsys) -> None:
    (tmp_path / "c.yaml").write_text("rgraph: 1\nresources: {x: {kind: imag}}\n")
    code, err = _validate(tmp_path, capsys, "rgraph: 1\n\ninclude: [c.yaml]\n")
    assert code == 2
    assert err.strip().endswith(f"(included from {tmp_path / 'g.yaml'}:3:11)")


def test_allow_include_outside(tmp_path: Path, capsys) -> None:
    (tmp_path / "shared.yaml").write_text("rgraph: 1\nparams: {s: 1}\n")
    (tmp_path / "sub").mkdir()
    path = tmp_path / "sub" / "g.yaml"
    path.write_text("rgraph: 1\ninclude: [../shared.yaml]\n")
    assert main(["validate", str(path)]) == 2
    assert "lies outside" in capsys.readouterr().err
    assert main(["validate", str(path), "--allow-include-outside"]) == 0


@pytest.mark.parametrize("scene", ["/dev/zero", "fifo", "dir"])
def test_scene_must_be_a_regular_file(tmp_path: Path, capsys, scene: str) -> None:
    if scene == "fifo":
        os.mkfifo(tmp_path / "fifo")
        scene = str(tmp_path / "fifo")
    elif scene == "dir":
        scene = str(tmp_path)
    began = time.perf_counter()
    code, err = _validate(tmp_path, capsys, "rgraph: 1\n", "--scene", scene)
    assert code == 2 and time.perf_counter() - began < 5
    assert err.startswith(f"{scene}:1:1: error: ") and ("not a regular file" in err or "is a directory" in err)


def test_too_many_keys_in_one_mapping_is_bounded(tmp_path: Path, capsys) -> None:
    from rgraph.spec import yaml_events

    old = yaml_events.MAX_KEYS
    yaml_events.MAX_KEYS = 100
    try:
        code, err = _validate(tmp_path, capsys, "rgraph: 1\nparams:\n" + "".join(f"  k{i}: {i}\n" for i in range(200)))
    finally:
        yaml_events.MAX_KEYS = old
    assert code == 2 and f"{tmp_path / 'g.yaml'}:103:3: error: more than 100 keys in one mapping" in err
