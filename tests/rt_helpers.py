"""Running the ray tracing graphs in tests (lavapipe): one compile and run, outputs read back."""

from __future__ import annotations

from typing import Any

import pytest

from rgraph.compiler.pipeline import compile_graph
from rgraph.vk.errors import VulkanUnavailable


def rt_validates() -> bool:
    """Whether ``--validate`` can run raytrace passes here: the layer setup installs (1.4.309)
    can; Debian 12's 1.3.239, left when setup could not fetch it, crashes on ray tracing
    pipelines, and ray tracing then runs unvalidated (tests/vk/test_bundled_layer.py says why)."""
    from rgraph.vk.probe_rt import layer_crashes

    try:
        return not layer_crashes()
    except VulkanUnavailable:  # pragma: no cover - no Vulkan: the device tests skip anyway
        return False


def run_rt(graph: str, scene: Any, size: tuple[int, int], params: dict | None = None, extra=(),
           frames: int = 1) -> tuple[dict, dict]:
    """(plan, outputs) of ``frames`` frames of ``graph`` on ``scene`` under validation and
    synchronization validation (where :func:`rt_validates`); skipped without Vulkan, and no
    validation message allowed."""
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(graph, scene_path=scene, size=size, params=params or {}, extra_outputs=list(extra))
    try:
        result = execute_plan(plan, validate=rt_validates(), frames=frames, read_outputs=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert result.messages == []
    return plan, result.outputs
