"""The probe's pure parts: exact codecs, the CPU simulation, the profile rule fitter."""

from __future__ import annotations

import pytest
from vkplans import PlanBuilder

from rgraph.memory_requirements import ProfileMemoryRequirements, fit_image_rule, predict_image
from rgraph.probe.check import compare_image
from rgraph.probe.simulate import simulate
from rgraph.probe.values import codec, seed


@pytest.mark.parametrize("fmt", ["R8G8B8A8_UNORM", "R8G8B8A8_SRGB", "R16G16B16A16_SFLOAT", "R32_UINT",
                                 "R16_SNORM", "D32_SFLOAT", "D16_UNORM", "R32G32_SFLOAT"])
def test_codec_round_trips_every_value_class(fmt):
    c = codec(fmt)
    for value in (0, 1, c.modulus // 2, c.modulus - 1):
        decoded = c.decode(c.encode(value) * 3)
        assert decoded.tolist() == [value] * (3 * c.components)


def test_codec_refuses_formats_without_exact_values():
    assert codec("BC1_RGB_UNORM_BLOCK") is None
    assert codec("A2B10G10R10_UNORM_PACK32") is None


def test_simulation_chains_reads_into_writes_and_accumulates_history():
    b = PlanBuilder((8, 8))
    b.image("history", "R32_UINT", lifetime="persistent").image("out", "R32_UINT", lifetime="output")
    b.add_pass("accumulate", "compute", [("history", "storage_rw")])
    b.add_pass("present", "compute", [("history", "storage_read"), ("out", "storage_write")])
    plan = b.build()
    one, three = simulate(plan, 1), simulate(plan, 3)
    m = codec("R32_UINT").modulus
    h1 = one[("history", 0, 0)]
    assert one[("out", 0, 0)] == (seed(1, 0) + h1) % m
    assert three[("history", 0, 0)] == (h1 + 2 * seed(0, 0)) % m


def test_undefined_reads_are_unknown_not_guessed():
    b = PlanBuilder((8, 8))
    b.image("out", "R32_UINT", lifetime="output")
    b.add_pass("rw", "compute", [("out", "storage_rw")])
    assert simulate(b.build())[("out", 0, 0)] is None


def test_compare_reports_a_wrong_texel():
    res = {"name": "x", "format": "R8G8B8A8_UNORM"}
    good = codec("R8G8B8A8_UNORM").encode(5) * 4
    assert compare_image(res, (0, 0), good, 5) is None
    bad = good[:-4] + codec("R8G8B8A8_UNORM").encode(6)
    assert "6 x4" in str(compare_image(res, (0, 0), bad, 5))


def test_profile_rules_reproduce_their_samples_and_fitter_rejects_noise():
    profile = ProfileMemoryRequirements.named("lavapipe").profile
    entry = profile["formats"]["R8G8B8A8_UNORM"]
    assert entry["rule"] is not None
    for s in entry["samples"]:
        assert predict_image(entry["rule"], entry["block_bytes"], entry["block_extent"], s[0:3], s[3], s[4],
                             s[5]) == s[6]
    noisy = [tuple(s[:6]) + (s[6] + (7 if i == 3 else 0), s[7], s[8]) for i, s in enumerate(entry["samples"])]
    assert fit_image_rule(noisy, entry["block_bytes"], entry["block_extent"]) is None
