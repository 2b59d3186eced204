"""Every ```yaml example in docs/format.md validates as written (fragments are listed by name)."""

from __future__ import annotations

import re
import shutil

import pytest
from locations import ROOT

from rgraph.cli import main

DOC = ROOT / "docs" / "format.md"
FRAGMENTS = {"passes:\n  hbao:", "include: ["}  # pieces of a graph shown alone, not whole files


def blocks() -> list[str]:
    return re.findall(r"```yaml\n(.*?)```", DOC.read_text(), flags=re.S)


def test_every_example_is_checked_or_named_a_fragment():
    found = blocks()
    fragments = [b for b in found if any(b.startswith(f) for f in FRAGMENTS)]
    assert len(fragments) == len(FRAGMENTS), "a fragment marker matches no example (or several)"
    assert len(found) >= 8


@pytest.mark.parametrize("index", range(len(blocks())))
def test_example_validates(index, tmp_path, capsys):
    text = blocks()[index]
    if any(text.startswith(f) for f in FRAGMENTS):
        pytest.skip("a fragment of a graph, not a whole file (listed in FRAGMENTS)")
    shutil.copytree(ROOT / "graphs" / "scenes", tmp_path / "scenes")
    if text.startswith("scene: 1"):
        scene = tmp_path / "example_scene.yaml"
        scene.write_text(text)
        graph, extra = "surgery", ["--scene", str(scene)]
    else:
        graph = tmp_path / "example.yaml"
        graph.write_text(text if "rgraph: 1" in text else "rgraph: 1\n" + text)
        graph, extra = str(graph), []
    code = main(["validate", graph, *extra])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "warning" not in err or "outputs:" not in text, err
