"""Random valid graphs executed under validation + synchronization validation with data checks:
zero messages and exact data (a handful by default; RGRAPH_FUZZ_EXAMPLES raises it, `make fuzz`
runs the slow many-example variant)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rgraph.compile.pipeline import compile_spec, frontend
from rgraph.random_graph import random_graph, to_yaml
from rgraph.vk.errors import VulkanUnavailable

pytestmark = pytest.mark.vulkan

EXAMPLES = int(os.environ.get("RGRAPH_FUZZ_EXAMPLES", "8"))
SLOW_EXAMPLES = int(os.environ.get("RGRAPH_FUZZ_EXAMPLES", "200"))
POLICIES = ("dedicated", "aliased")


@pytest.fixture(scope="module")
def memory():
    """Memory requirements from the live device, so plans match it (lavapipe or a GPU)."""
    try:
        from rgraph.vk.device import create_device
        from rgraph.vk.instance import create_instance
        from rgraph.vk.memreq import DeviceMemoryRequirements

        instance = create_instance(validate=False)
        device = create_device(instance, None, verbose=False)
    except VulkanUnavailable as exc:  # pragma: no cover - environment without Vulkan
        pytest.skip(str(exc))
    yield DeviceMemoryRequirements(device)
    device.destroy()
    instance.destroy()


def run_random(tmp: Path, memory, seed: int, passes: int, policy: str) -> None:
    from rgraph.vk.executor import execute_plan

    path = tmp / f"g_{seed}_{passes}.yaml"
    path.write_text(to_yaml(random_graph(seed, passes)))
    plan = compile_spec(frontend(path, size=(16, 16)).spec, policy=policy, memory_provider=memory)
    result = execute_plan(plan, validate=True, frames=2, check_data=True)
    where = f"random_graph(seed={seed}, passes={passes}), policy {policy}"
    assert [str(m) for m in result.messages] == [], where
    assert result.data_ok is True, (where, [str(m) for m in result.mismatches[:5]])


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(1, 20), policy=st.sampled_from(POLICIES))
def test_fuzz_random_graphs_run_clean(tmp_path: Path, memory, seed: int, passes: int, policy: str) -> None:
    run_random(tmp_path, memory, seed, passes, policy)


@pytest.mark.slow
@settings(max_examples=SLOW_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10**6), passes=st.integers(1, 40), policy=st.sampled_from(POLICIES))
def test_fuzz_many_random_graphs_run_clean(tmp_path: Path, memory, seed: int, passes: int, policy: str) -> None:
    run_random(tmp_path, memory, seed, passes, policy)
