"""`rgraph run`'s note when rays are traced against a scene with skinned meshes (they stay in
their rest pose in acceleration structures), and its absence otherwise."""

from __future__ import annotations

import pytest

from rgraph.commands.run import rest_pose_note
from rgraph.compiler.pipeline import compile_graph


@pytest.mark.parametrize(("graph", "scene", "noted"), [
    ("rt_standalone", "graphs/scenes/vr_skinned.yaml", True),
    ("rt_hybrid", "graphs/scenes/vr_skinned.yaml", True),
    ("rt_standalone", "graphs/scenes/rt_tiny.yaml", False),
    ("clustered", "graphs/scenes/vr_skinned.yaml", False),  # raster: the vertex shader animates them
])
def test_rest_pose_note(graph: str, scene: str, noted: bool) -> None:
    plan = compile_graph(graph, scene_path=scene, size=(32, 16))
    note = rest_pose_note(plan)
    if noted:
        assert note is not None and "1 skinned mesh(es)" in note and "rest pose" in note
    else:
        assert note is None
