"""``rgraph device-profile``: buffer rules fitted per usage (NVIDIA rounds sizes differently per
usage: the capture failed there with a traceback), clean errors, and a captured profile that
reproduces the live device's plan."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from locations import TESTS

from rgraph.memory_requirements import ProfileMemoryRequirements, align_up
from rgraph.vk.profile_capture import BUFFER_USAGES, ProfileCaptureError, _measure_buffers


class FakeBufferRequirements:
    """Per-usage size rounding and alignment; combinations take the largest (pure logic)."""

    def __init__(self, size_align: dict[str, int], alignment: dict[str, int], combine_max: bool = True) -> None:
        self.size_align, self.alignment, self.combine_max = size_align, alignment, combine_max

    def buffer(self, size: int, usages: list[str]) -> tuple[int, int, int]:
        rounding = [self.size_align[u] for u in usages]
        step = max(rounding) if self.combine_max else min(rounding)
        return align_up(max(size, 1), step), max(self.alignment[u] for u in usages), 0b111


NVIDIA_LIKE_SIZES = {u: 4 for u in BUFFER_USAGES} | {"uniform": 256, "index": 16}
NVIDIA_LIKE_ALIGN = {u: 16 for u in BUFFER_USAGES} | {"uniform": 256, "storage_rw": 64}


def test_buffer_rule_per_usage_predicts_single_and_combined_usages() -> None:
    rule = _measure_buffers(FakeBufferRequirements(NVIDIA_LIKE_SIZES, NVIDIA_LIKE_ALIGN))
    assert rule["size_align_by_usage"] == NVIDIA_LIKE_SIZES
    profile = ProfileMemoryRequirements({"format": "rgraph-device-profile/1", "buffer": rule, "formats": {}})
    fake = FakeBufferRequirements(NVIDIA_LIKE_SIZES, NVIDIA_LIKE_ALIGN)
    for usages in (["vertex"], ["uniform", "storage_rw"], ["index", "indirect"], list(BUFFER_USAGES)):
        for size in (1, 13, 4097):
            assert profile.buffer(size, usages) == fake.buffer(size, usages), (usages, size)


def test_buffer_rules_a_profile_cannot_describe_are_named() -> None:
    with pytest.raises(ProfileCaptureError, match="usages .*\\+"):
        _measure_buffers(FakeBufferRequirements(NVIDIA_LIKE_SIZES, NVIDIA_LIKE_ALIGN, combine_max=False))

    class OddRounding(FakeBufferRequirements):
        def buffer(self, size: int, usages: list[str]) -> tuple[int, int, int]:
            got = super().buffer(size, usages)
            return (got[0] + 3 if "vertex" in usages else got[0]), got[1], got[2]

    with pytest.raises(ProfileCaptureError, match="usage vertex follow no power-of-two rounding"):
        _measure_buffers(OddRounding(NVIDIA_LIKE_SIZES, NVIDIA_LIKE_ALIGN))


def test_profiles_without_per_usage_rounding_still_load() -> None:
    profile = ProfileMemoryRequirements.named("lavapipe")
    assert profile.buffer(1000, ["storage_rw", "uniform"])[0] >= 1000


@pytest.mark.vulkan
def test_captured_profile_compiles_the_plan_the_live_device_gets(tmp_path: Path) -> None:
    """End to end: capture the default device's profile with the CLI, then compile a bundled
    graph offline with it; the plan's memory layout equals the one compiled against the device."""
    from rgraph.api import compile_for_device
    from rgraph.compiler.pipeline import compile_graph

    out = tmp_path / "device.json"
    formats = "R8G8B8A8_UNORM,R16G16B16A16_SFLOAT,R32_SFLOAT,D32_SFLOAT,B10G11R11_UFLOAT_PACK32"
    run = subprocess.run([sys.executable, "-m", "rgraph", "device-profile", "-o", str(out), "--formats",
                          formats], capture_output=True, text=True)
    if run.returncode != 0 and "Vulkan" in run.stderr:  # pragma: no cover - no Vulkan here
        pytest.skip(run.stderr)
    assert run.returncode == 0, run.stderr
    assert "Traceback" not in run.stderr
    captured = json.loads(out.read_text())
    assert set(captured["buffer"]["size_align_by_usage"]) == set(BUFFER_USAGES)
    graph = "graphs/allocator_lines.yaml"
    try:
        offline = compile_graph(graph, size=(64, 64), memory=ProfileMemoryRequirements.from_file(out))
    except Exception as exc:  # noqa: BLE001 - a format outside --formats: say which
        pytest.fail(f"offline compile with the captured profile failed: {exc}")
    live = compile_for_device(graph, size=(64, 64))
    layout = lambda plan: [(r["name"], r["bytes"], r.get("heap"), r.get("offset")) for r in plan["resources"]]  # noqa: E731
    assert layout(offline) == layout(live)
    assert offline["heaps"] == live["heaps"]


H100_SAMPLES = TESTS / "data" / "h100_samples.json"  # measured: rgraph device-profile, H100


@pytest.mark.parametrize("fmt", ["R8G8B8A8_UNORM", "R16G16B16A16_SFLOAT", "D32_SFLOAT"])
def test_block_linear_rule_predicts_measured_h100_sizes(fmt: str) -> None:
    """NVIDIA's image sizes fit no rule of the packed family (the H100 capture kept 0 rules);
    the block-linear rule (64-byte x 8-row GOBs, block height adapting to the height) predicts
    every measured single-mip, single-sample size, and a profile using it refuses mip chains
    and MSAA at extents it did not measure instead of guessing."""
    from rgraph.memory_requirements import fit_block_linear_rule, fit_image_rule, predict_block_linear

    data = json.loads(H100_SAMPLES.read_text())
    entry = data["formats"][fmt]
    samples = [tuple(s) for s in entry["samples"]]
    assert fit_image_rule(samples, entry["block_bytes"], entry["block_extent"]) is None
    rule = fit_block_linear_rule(samples, entry["block_bytes"], entry["block_extent"])
    assert rule is not None and rule["family"] == "block_linear"
    entry["rule"] = rule
    profile = ProfileMemoryRequirements(data, str(H100_SAMPLES))
    inside = [s for s in samples if s[3] == 1 and s[5] == 1]
    assert len(inside) >= 10
    assert [predict_block_linear(rule, entry["block_bytes"], entry["block_extent"], s[0:3], s[4]) for s in inside] \
        == [s[6] for s in inside]
    unmeasured = profile.image(fmt, (96, 48, 1), 1, 2, 1, ["sampled"])  # 2D, one mip: the rule answers
    assert unmeasured[0] == predict_block_linear(rule, entry["block_bytes"], entry["block_extent"], (96, 48, 1), 2)
    with pytest.raises(Exception, match="single-mip, single-sample"):
        profile.image(fmt, (96, 48, 1), 3, 1, 1, ["sampled"])
