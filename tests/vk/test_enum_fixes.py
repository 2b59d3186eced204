"""The binding's enum values, as rgraph sees them, against the Vulkan registry (vk.xml through
the ``vulkan-object`` package): the binding (1.3.275.1) ignores vk.xml's ``extnumber`` and
gave, among others, VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR = 1000347000 (the right value is
1000165000), which lavapipe took for no bind point at all."""

from __future__ import annotations

import importlib

import pytest

vulkan_object = pytest.importorskip("vulkan_object")


def _registry_values() -> dict[str, int]:
    registry = vulkan_object.get_vulkan_object()
    values: dict[str, int] = {}
    for enum in registry.enums.values():
        for field in enum.fields:
            for name in (field.name, *(field.aliases or [])):
                values[name] = field.value
    for bitmask in registry.bitmasks.values():
        for flag in bitmask.flags:
            for name in (flag.name, *(flag.aliases or [])):
                values[name] = flag.value
    return values


def _mismatches(module) -> list[tuple[str, int, int]]:
    return [(name, getattr(module, name), value) for name, value in _registry_values().items()
            if getattr(module, name, None) is not None and getattr(module, name) != value]


def test_every_enum_value_rgraph_uses_is_the_registrys() -> None:
    from rgraph.vk.loader import vk

    assert _mismatches(vk()) == []


def test_the_binding_itself_still_needs_the_fixes() -> None:
    """If a new binding release fixes its generator, this fails: drop rgraph.vk.enum_fixes then.
    (``vulkan._vulkan`` holds the generated constants; rgraph's loader fixes ``vulkan``.)"""
    from rgraph.vk import enum_fixes

    generated = importlib.import_module("vulkan._vulkan")
    wrong = {name for name, _, _ in _mismatches(generated)}
    assert "VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR" in wrong
    assert wrong == set(enum_fixes.CORRECT)
