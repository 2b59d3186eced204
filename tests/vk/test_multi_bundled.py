"""Every bundled graph split across two logical devices of one physical device (lavapipe):
the composited output equals the one-device output bit for bit, for both splits, with zero
validation messages (the ray tracing graphs too, under the layer setup installs; where only
Debian 12's layer is there, which crashes on ray tracing pipelines, they run unvalidated)."""

from __future__ import annotations

import numpy as np
import pytest
from multi_helpers import outputs_one_and_split, validated_pair
from rt_helpers import rt_validates

from rgraph.api import open_device
from rgraph.resources import bundled_graphs

SIZE = (32, 24)
COVERED_ELSEWHERE = {"surgery"}  # tests/vk/test_multi_device.py
RAY_TRACING = {"rt_standalone", "rt_hybrid", "rt_hybrid_raster"}
VALIDATED = sorted(set(bundled_graphs()) - COVERED_ELSEWHERE - (set() if rt_validates() else RAY_TRACING))
UNVALIDATED = sorted(set(bundled_graphs()) - COVERED_ELSEWHERE - set(VALIDATED))
MODES = ["sort-first", "sort-last"]


@pytest.fixture(scope="module")
def gpus():
    yield from validated_pair()


@pytest.fixture(scope="module")
def unvalidated_gpus():
    devices = [open_device(validate=False, device=0, verbose=False) for _ in range(2)]
    try:
        yield devices
    finally:
        for d in devices:
            d.close()


def test_every_bundled_graph_is_split():
    assert set(bundled_graphs()) - COVERED_ELSEWHERE == set(VALIDATED) | set(UNVALIDATED)


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


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("graph", UNVALIDATED)
def test_ray_tracing_graph_split_equals_one_device_unvalidated(unvalidated_gpus, graph, mode):
    _assert_equal_outputs(*outputs_one_and_split(unvalidated_gpus, graph, mode, SIZE))
