import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import pytest  # noqa: E402


@pytest.fixture(scope="module")
def memory():
    """Memory requirements from the live device, so plans match it (lavapipe or a GPU)."""
    from rgraph.vk.errors import VulkanUnavailable
    from rgraph.vk.memreq import live_requirements

    try:
        with live_requirements() as (requirements, _device):
            yield requirements
    except VulkanUnavailable as exc:  # pragma: no cover - environment without Vulkan
        pytest.skip(str(exc))


# Folders whose tests need a Vulkan device: every test there carries the ``vulkan`` marker
# (``pytest -m "not vulkan"`` runs the device-free rest).
VULKAN_FOLDERS = frozenset({"vk", "passes", "sweep", "mutate"})


def pytest_collection_modifyitems(config, items):
    tests = Path(__file__).parent
    for item in items:
        parts = Path(str(item.fspath)).relative_to(tests).parts
        if parts and parts[0] in VULKAN_FOLDERS:
            item.add_marker(pytest.mark.vulkan)
