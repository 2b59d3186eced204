"""The compiled elastic dive (``rgraph/memory/_dive.pyx``) against ``elastic.dive_python``:
the same ``Dive`` (offsets, peak, blamed blocks, operations) everywhere, cut-offs included."""

from __future__ import annotations

import importlib
import os
import random
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_memory_search import hard_trace
from test_minimalloc_exact import block_lists

from rgraph.memory import elastic
from rgraph.memory.aliased import ELASTIC_ORDERS, place_class
from rgraph.memory.elastic import Dive, dive_python, improve, native_dive
from rgraph.memory.instance import Instance
from rgraph.memory.model import Block
from rgraph.memory.random_instances import random_blocks
from rgraph.memory.search import preorder
from rgraph.memory.trace import read_trace

try:  # straight from the build, whatever RGRAPH_NATIVE says
    NATIVE = importlib.import_module("rgraph.memory._dive")
except ImportError:
    NATIVE = None

pytestmark = pytest.mark.skipif(NATIVE is None, reason="rgraph.memory._dive not built (setup.py build_ext)")

ROOT = Path(__file__).resolve().parents[2]
#: ``$RGRAPH_SHARED``, else ``shared/`` beside the checkout (or beside ``wt/`` for a worktree).
SHARED = [Path(os.environ["RGRAPH_SHARED"])] if "RGRAPH_SHARED" in os.environ else [ROOT.parent / "shared", ROOT.parents[1] / "shared"]
TRACES = next((p / "data/minimalloc" for p in SHARED if (p / "data/minimalloc").is_dir()), SHARED[0] / "data/minimalloc")


def as_tuple(found: Dive | None) -> tuple | None:
    return None if found is None else (found.offsets, found.peak, found.blamed, found.ops)


def assert_same_dives(inst: Instance, order: list[int], capacity: int) -> int:
    """Both dives agree in full, under an operation limit and with a give-up capacity;
    returns how many dives were compared."""
    full = dive_python(inst, order, capacity)
    assert full is not None
    assert as_tuple(native_dive(NATIVE, inst, order, capacity)) == as_tuple(full)
    compared = 1
    for limit in {0, full.ops // 7, full.ops // 2, full.ops - 1, full.ops}:
        python = dive_python(inst, order, capacity, ops_limit=limit)
        assert as_tuple(native_dive(NATIVE, inst, order, capacity, ops_limit=limit)) == as_tuple(python), limit
        compared += 1
    bound = inst.lower_bound()
    for give_up in {bound, (bound + full.peak) // 2 + 1, full.peak, full.peak + 1}:
        python = dive_python(inst, order, capacity, give_up_at=give_up)
        assert as_tuple(native_dive(NATIVE, inst, order, capacity, give_up_at=give_up)) == as_tuple(python), give_up
        compared += 1
    return compared


def test_random_instances_give_identical_dives():
    compared, raised = 0, 0
    for seed in range(12):
        for count in (12, 60, 180):
            blocks = random_blocks(count, seed)
            for cls in ("device_local_optimal", "device_local_linear"):
                inst = Instance.build([b for b in blocks if b.memory_class == cls])
                orders = [preorder(inst, h) for h in ELASTIC_ORDERS]
                shuffled = list(range(inst.n))
                random.Random(seed).shuffle(shuffled)
                for order in [*orders, shuffled]:
                    for capacity in (inst.lower_bound(), inst.lower_bound() * 9 // 8, 0):
                        compared += assert_same_dives(inst, order, capacity)
                        found = dive_python(inst, order, capacity)
                        raised += bool(found and found.blamed)
    assert compared > 2000 and raised > 20  # the raises (the blamed lists) were compared too


def test_hard_traces_give_identical_dives_and_improve_runs(monkeypatch):
    for seed in range(4):
        inst = Instance.build(hard_trace(150, seed))
        orders = [preorder(inst, h) for h in ELASTIC_ORDERS]
        for order in orders:
            assert_same_dives(inst, order, inst.lower_bound())
        compiled = improve(inst, orders, 10**9, 3_000_000)
        monkeypatch.setattr(elastic, "NATIVE", None)
        python = improve(inst, orders, 10**9, 3_000_000)
        monkeypatch.setattr(elastic, "NATIVE", NATIVE)
        assert compiled == python and compiled.dives > 3


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=block_lists(30, 20, 10, 300, [1, 2, 16, 64], "c"), rank=st.randoms(use_true_random=False))
def test_small_instances_with_empty_blocks_give_identical_dives(blocks, rank):
    inst = Instance.build(blocks)
    order = list(range(inst.n))
    rank.shuffle(order)
    assert_same_dives(inst, order, inst.lower_bound())


def symmetric_conflicts(names: list[str], pairs: int, seed: int) -> dict[str, set[str]]:
    """``pairs`` random pairs of ``names`` that may not share memory, both ways."""
    rng = random.Random(seed)
    conflicts: dict[str, set[str]] = {}
    for _ in range(pairs):
        a, b = rng.sample(names, 2)
        conflicts.setdefault(a, set()).add(b)
        conflicts.setdefault(b, set()).add(a)
    return conflicts


def test_conflicts_apart_in_time_give_identical_dives():
    blocks = hard_trace(80, 7)
    inst = Instance.build(blocks, symmetric_conflicts([b.name for b in blocks], 60, 3))
    assert not inst.separable
    for h in ELASTIC_ORDERS:
        assert_same_dives(inst, preorder(inst, h), inst.lower_bound())


def test_the_flat_copy_is_made_once_per_instance():
    inst = Instance.build(hard_trace(40, 1))
    order = preorder(inst, "TAW")
    native_dive(NATIVE, inst, order, inst.lower_bound())
    flat = inst.accelerated["dive"]
    native_dive(NATIVE, inst, order, inst.lower_bound())
    assert inst.accelerated["dive"] is flat


def test_bad_input_is_refused_not_crashed():
    inst = Instance.build([Block("a", 0, 1, 16, 4, "c"), Block("b", 1, 2, 8, 4, "c")])
    with pytest.raises(IndexError):
        native_dive(NATIVE, inst, [0, 5], inst.lower_bound())


def test_place_class_is_the_same_without_the_compiled_dive(monkeypatch):
    blocks = hard_trace(120, 5)
    compiled = place_class(Instance.build(blocks), 0.05)
    monkeypatch.setattr(elastic, "NATIVE", None)
    python = place_class(Instance.build(blocks), 0.05)
    assert compiled.how.startswith("elastic:")
    assert (compiled.offsets, compiled.peak, compiled.how, compiled.proven) == (
        python.offsets, python.peak, python.how, python.proven)


@pytest.mark.skipif(not TRACES.is_dir(), reason="MiniMalloc traces not present (RGRAPH_SHARED)")
@pytest.mark.parametrize("name", ["A", "D", "H", "K"])
def test_minimalloc_traces_give_identical_dives(name):
    inst = Instance.build(read_trace(TRACES / f"{name}.1048576.csv"))
    for h in ELASTIC_ORDERS:
        order = preorder(inst, h)
        full = dive_python(inst, order, inst.lower_bound())
        assert full is not None and full.blamed  # raises happened
        assert as_tuple(native_dive(NATIVE, inst, order, inst.lower_bound())) == as_tuple(full)
        assert native_dive(NATIVE, inst, order, inst.lower_bound(), ops_limit=full.ops // 3) is None
        for limit in (full.ops // 3, full.ops - 1):  # checked per step: the last steps may pass it
            assert as_tuple(native_dive(NATIVE, inst, order, inst.lower_bound(), ops_limit=limit)) == as_tuple(
                dive_python(inst, order, inst.lower_bound(), ops_limit=limit))
        give_up = (inst.lower_bound() + full.peak) // 2
        assert as_tuple(native_dive(NATIVE, inst, order, inst.lower_bound(), give_up_at=give_up)) == as_tuple(
            dive_python(inst, order, inst.lower_bound(), give_up_at=give_up))
