"""Every bundled graph split across two logical devices of one physical device (lavapipe):
the composited output equals the one-device output bit for bit, for both splits, with zero
validation messages (the ray tracing graphs too, since session 21's validation layer)."""

from __future__ import annotations

import numpy as np
import pytest
from multi_helpers import outputs_one_and_split, validated_pair

from rgraph.resources import bundled_graphs

SIZE = (32, 24)
COVERED_ELSEWHERE = {"surgery"}  # tests/vk/test_multi_device.py
VALIDATED = sorted(set(bundled_graphs()) - COVERED_ELSEWHERE)
MODES = ["sort-first", "sort-last"]


@pytest.fixture(scope="module")
def gpus():
    yield from validated_pair()


def test_the_ray_tracing_graphs_are_split_under_validation_too():
    assert {"rt_standalone", "rt_hybrid", "rt_hybrid_raster"} <= set(VALIDATED)


def _assert_equal_outputs(plan, one, out):
    names = [r["name"] for r in plan["resources"] if r["lifetime"] == "output"]
    assert names
    for name in names:
        assert np.array_equal(np.asarray(one[name]), np.asarray(out[name])), name


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("graph", VALIDATED)
def test_bundled_graph_split_equals_one_device(gpus, graph, mode):
    plan, one, out = outputs_one_and_split(gpus, graph, mode, SIZE)
    _assert_equal_outputs(plan, one, out)
    assert [str(m) for g in gpus for m in g.instance.log.messages] == []
