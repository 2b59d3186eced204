"""The validation layer ``scripts/validation_layer.py`` installs (Debian 13's 1.4.309, made to load
on Debian 12): setup put it in the venv, ``--validate`` uses it, and it checks ray tracing
pipelines (Debian 12's 1.3.239 crashed creating them)."""

from __future__ import annotations

import pytest
from locations import TESTS

from rgraph.compiler.pipeline import compile_graph
from rgraph.vk.errors import VulkanUnavailable

pytestmark = pytest.mark.vulkan


def _installed() -> None:
    """Skip with setup's reason when it could not install the layer (no network, say): the ray
    tracing tests then run unvalidated; fail when setup did not run."""
    from rgraph.vk.bundled_layer import bundled_layer_dir, why_unavailable

    if bundled_layer_dir() is None and why_unavailable():
        pytest.skip(f"setup could not install the validation layer: {why_unavailable()}")
    assert bundled_layer_dir() is not None, "run scripts/setup.sh (it installs the layer into .venv)"


def test_setup_installed_a_layer_that_can_validate_ray_tracing() -> None:
    from rgraph.vk.instance import validation_layer_version
    from rgraph.vk.probe_rt import CRASHING_LAYER

    _installed()
    version = validation_layer_version()
    assert version is not None and version > CRASHING_LAYER, version


def test_the_layer_reports_a_wrong_ray_tracing_structure_type(monkeypatch) -> None:
    """The binding's own value of VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR (what
    rgraph passed until session 21) is reported; rgraph's is not (test_rt_runtime.py)."""
    from rgraph.vk.executor import execute_plan
    from rgraph.vk.loader import vk

    _installed()
    v = vk()
    monkeypatch.setattr(v, "VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR", 1000347015)
    plan = compile_graph(TESTS / "data" / "rt" / "rt_probe.yaml", size=(8, 8))
    try:
        result = execute_plan(plan, validate=True, frames=1)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert any("VUID-VkRayTracingPipelineCreateInfoKHR-sType-sType" in m.id_name for m in result.messages)


def test_devices_names_the_layer_validate_uses(capsys) -> None:
    from rgraph.cli import main
    from rgraph.vk.bundled_layer import bundled_layer_dir

    _installed()
    assert main(["devices"]) == 0
    err = capsys.readouterr().err
    assert "--validate uses Khronos validation layer 1.4." in err and str(bundled_layer_dir()) in err, err
