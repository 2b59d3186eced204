"""Acceleration-structure sizes in device profiles (rgraph.accel_profile): the affine rule
fit, prediction from rules and samples, refusals; the bundled lavapipe section equals a fresh
capture on the live device."""

from __future__ import annotations

import json

import pytest

from rgraph.accel_profile import fit_affine, fit_level, predict
from rgraph.errors import RGraphError
from rgraph.memory_requirements import PROFILES_DIR


def test_affine_fit_finds_where_the_rule_starts():
    pts = [(1, 144)] + [(n, 104 * n - 16) for n in (2, 3, 12, 100, 1000)]
    assert fit_affine(pts) == {"a": 104, "b": -16, "from": 2}
    assert fit_affine([(1, 1), (2, 4), (3, 9), (4, 16)]) is None  # quadratic: only the top two fit
    assert fit_affine([(1, 3), (4, 5)]) is None  # too few points


def test_sizes_that_depend_on_the_vertex_count_get_no_rule():
    samples = [[n, mv, 0, 100 * n + mv, 64, 64] for n in (1, 2, 3, 4) for mv in (3 * n - 1, 2)]
    assert fit_level(samples) is None


def test_prediction_from_samples_and_rules_and_refusal():
    samples = [[1, 2, 0, 144, 64, 64]] + [[n, 3 * n - 1, 0, 104 * n - 16, 64, 64] for n in (2, 3, 4, 100)]
    section = {"bottom": {"samples": samples, "rules": fit_level(samples)}}
    assert predict(section, "bottom", 1, 7, False, "p") == (144, 64, 64)  # measured sample
    assert predict(section, "bottom", 5000, 9, False, "p") == (104 * 5000 - 16, 64, 64)
    with pytest.raises(RGraphError, match="no verified bottom-level size rule"):
        predict(section, "bottom", 10, 3, True, "p")  # updates were not measured
    with pytest.raises(RGraphError, match="no top-level sizes"):
        predict(section, "top", 1, 0, False, "p")


@pytest.mark.vulkan
def test_bundled_lavapipe_accel_section_equals_a_fresh_capture():
    from rgraph.vk.accel_capture import capture_accel
    from rgraph.vk.device import create_device
    from rgraph.vk.errors import VulkanUnavailable
    from rgraph.vk.instance import create_instance

    try:
        instance = create_instance(False)
        device = create_device(instance, None, verbose=False, ray_tracing=True)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    try:
        if "llvmpipe" not in device.name:
            pytest.skip("the bundled profile is lavapipe's")
        captured = capture_accel(device)
    finally:
        device.destroy()
        instance.destroy()
    bundled = json.loads((PROFILES_DIR / "lavapipe.json").read_text())["accel"]
    assert json.loads(json.dumps(captured)) == bundled
