"""Issue 18's scenes (instanced, unique, skinned; clustered.yaml, stereo, --naive-cpu, --logic-hz)
with inputs written from FORMAT.md 7 by a hostile user, second round (tests/fixtures/unseen/bad/
vr_scenes and scenes/). Each bug these inputs found stays fixed:

- scene values of the wrong type were coerced silently (``unique: "yes"``, ``deformable: "no"``,
  ``count: true``, ``position: ["1", ...]``, ``grid: [2, 2.0, 2]``): scene models are strict now,
  like the graph's, and each is a located error.
"""

from __future__ import annotations

import pytest
from locations import TESTS
from test_unseen_inputs import _diagnostics

BAD = TESTS / "fixtures" / "unseen" / "bad" / "vr_scenes"


def test_wrong_types_in_scene_values_are_located_errors(capsys) -> None:
    path = str(BAD / "wrong_types.yaml")
    rc, diags = _diagnostics(capsys, ["validate", "clustered", "--scene", path])
    assert rc == 2
    got = [(d["file"], d["line"], d["col"], d["message"]) for d in diags]
    assert got == [
        (path, 6, 57, "expected true or false for 'shadows', got string 'true'"),
        (path, 9, 39, "expected true or false for 'unique', got string 'yes'"),
        (path, 10, 43, "expected true or false for 'deformable', got string 'no'"),
        (path, 11, 50, "expected an integer for 'count', got boolean true"),
        (path, 12, 42, "expected a number for 'position', got string '1'"),
        (path, 13, 53, "expected an integer for 'grid', got number 2.0"),
    ]
