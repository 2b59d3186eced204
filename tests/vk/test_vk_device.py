"""Device, instance and teardown: validation catches leaks, the memory provider matches objects."""

from __future__ import annotations

import pytest
from vkplans import PlanBuilder

from rgraph.vk.errors import VulkanUnavailable

pytestmark = pytest.mark.vulkan


def _plan():
    b = PlanBuilder((16, 16))
    b.image("out", "R8G8B8A8_UNORM", lifetime="output")
    b.add_pass("draw", "raster", [("out", "color_attachment")])
    return b.build()


def _executor(plan):
    from rgraph.vk.executor import Executor

    try:
        return Executor(plan, validate=True, device_index=None, verbose=False)
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))


def test_teardown_leaks_nothing_and_a_planted_leak_is_reported():
    from rgraph.vk.loader import vk

    clean = _executor(_plan())
    clean.run_frames(2)
    assert clean.close() == []

    leaky = _executor(_plan())
    v = vk()
    info = v.VkBufferCreateInfo(size=64, usage=v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                sharingMode=v.VK_SHARING_MODE_EXCLUSIVE)
    v.vkCreateBuffer(leaky.device.handle, info, None)  # never destroyed
    messages = leaky.close()
    assert any("VkBuffer" in m.text and "destroy" in m.text.lower() for m in messages), [str(m) for m in messages]


def test_device_memory_requirements_match_the_lavapipe_profile():
    from rgraph.memory_requirements import ProfileMemoryRequirements
    from rgraph.vk.device import create_device
    from rgraph.vk.instance import create_instance
    from rgraph.vk.memreq import DeviceMemoryRequirements

    instance = create_instance(validate=False)
    try:
        device = create_device(instance, verbose=False)
        if "llvmpipe" not in device.name:  # pragma: no cover
            pytest.skip("the checked-in profile is lavapipe's")
        live, offline = DeviceMemoryRequirements(device), ProfileMemoryRequirements.named("lavapipe")
        cases = [("R8G8B8A8_UNORM", (1280, 720, 1), 1, 1), ("D32_SFLOAT", (333, 221, 1), 3, 2),
                 ("R16G16B16A16_SFLOAT", (97, 1031, 1), 5, 4), ("R32_UINT", (7, 7, 1), 1, 6)]
        for fmt, extent, mips, layers in cases:
            assert live.image(fmt, extent, mips, layers, 1, ["sampled"]) == offline.image(
                fmt, extent, mips, layers, 1, ["sampled"]), fmt
        assert live.buffer(1000, ["storage_rw", "uniform"]) == offline.buffer(1000, ["storage_rw", "uniform"])
        device.destroy()
    finally:
        instance.destroy()


def test_plan_size_mismatch_names_the_resource():
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.executor import execute_plan

    plan = _plan()
    plan["resources"][0]["bytes"] += 64
    plan["heaps"][0]["bytes"] += 64
    with pytest.raises(ExecutionError, match="'out'"):
        execute_plan(plan, validate=False)
