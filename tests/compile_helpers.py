"""Helpers for compiler tests: compile YAML text into a plan dict."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

from rgraph.compiler.pipeline import compile_graph


def compile_text(tmp_path: Path, text: str, *, size=(64, 64), policy="dedicated", scene: str | None = None, **kw) -> dict[str, Any]:
    path = tmp_path / "g.yaml"
    path.write_text(textwrap.dedent(text))
    scene_path = None
    if scene is not None:
        scene_path = tmp_path / "s.yaml"
        scene_path.write_text(textwrap.dedent(scene))
    return compile_graph(path, scene_path=scene_path, size=size, policy=policy, **kw)


def barriers_of(plan: dict, pass_name: str) -> list[dict]:
    return next(p for p in plan["passes"] if p["name"] == pass_name)["barriers"]


def pass_named(plan: dict, name: str) -> dict:
    return next(p for p in plan["passes"] if p["name"] == name)
