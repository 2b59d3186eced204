"""Scene files with hostile numbers get a located error from validate, never a crash or OOM."""

from __future__ import annotations

from pathlib import Path

import pytest

from rgraph.cli import main

CASES = [
    ("nan_position", "camera: {position: [.nan, 0, 1]}", (2, 21), "finite number"),
    ("inf_position", "camera: {position: [.inf, 0, 1]}", (2, 21), "finite number"),
    ("looks_nowhere", "camera: {position: [1, 1, 1], look_at: [1, 1, 1]}", (2, 9), "must differ from 'position'"),
    ("zero_up", "camera: {up: [0, 0, 0]}", (2, 9), "'up' must not be zero"),
    ("huge_grid", "materials: {m: {}}\nmeshes: [{shape: box, material: m, instances: {grid: [100000, 100000, 100000]}}]",
     (3, 47), "over the limit of 1,048,576"),
    ("huge_segments", "materials: {m: {}}\nmeshes: [{shape: sphere, material: m, params: {segments: 1000000000}}]",
     (3, 58), "'segments' must be in 1..4096"),
    ("huge_count", "materials: {m: {}}\nmeshes: [{shape: segments, material: m, params: {count: 100000000}}]",
     (3, 57), "'count' must be in 1..1024"),
    ("fine_sphere", "materials: {m: {}}\nmeshes: [{shape: sphere, material: m, params: {segments: 4000, rings: 4000}}]",
     (3, 47), "too finely divided"),
    ("inf_radius", "materials: {m: {}}\nmeshes: [{shape: sphere, material: m, params: {radius: .inf}}]", (3, 56),
     "finite number"),
    ("text_segments", "materials: {m: {}}\nmeshes: [{shape: sphere, material: m, params: {segments: 2.5}}]", (3, 58),
     "must be an integer"),
]


@pytest.mark.parametrize("name,body,where,message", CASES, ids=[c[0] for c in CASES])
def test_hostile_scene(tmp_path: Path, capsys, name, body, where, message) -> None:
    (tmp_path / "g.yaml").write_text("rgraph: 1\n")
    scene = tmp_path / "s.yaml"
    scene.write_text("scene: 1\n" + body + "\n")
    assert main(["validate", str(tmp_path / "g.yaml"), "--scene", str(scene)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{scene}:{where[0]}:{where[1]}: error: "), lines
    assert message in lines[0]
