"""The compiled best fit (``rgraph/memory/_fit.pyx``) against ``greedy.best_fit_python``: the
same offsets and the same give-ups everywhere (sparse and dense instances, matrix and
neighbour lists, empty blocks, the MiniMalloc traces), and its helpers for ``Instance.build``
(``conflict_matrix``) and ``bounds.clique_bound`` (``clique_extra``) against their Python code."""

from __future__ import annotations

import importlib
import random
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_best_fit_paths import instance, plain_best_fit
from test_elastic_native import TRACES, symmetric_conflicts
from test_minimalloc_exact import block_lists

from rgraph.memory import bounds, greedy, place
from rgraph.memory import instance as instance_module
from rgraph.memory.aliased import place_class
from rgraph.memory.greedy import best_fit_python, native_flat, orderings
from rgraph.memory.instance import SWEEP_FROM, Instance
from rgraph.memory.model import Block
from rgraph.memory.random_instances import random_blocks
from rgraph.memory.trace import read_trace

try:  # straight from the build, whatever RGRAPH_NATIVE says
    NATIVE = importlib.import_module("rgraph.memory._fit")
except ImportError:
    NATIVE = None

pytestmark = pytest.mark.skipif(NATIVE is None, reason="rgraph.memory._fit not built (setup.py build_ext)")


def native_fit(inst: Instance, order: list[int], give_up_at: int | None = None) -> list[int] | None:
    flat = native_flat(NATIVE, inst)
    assert flat is not None
    return NATIVE.best_fit(flat, order, give_up_at)


def cut_offs(inst: Instance, order: list[int], offsets: list[int]) -> list[int | None]:
    """Give-up capacities around the placement: none, the peak and either side of it, each
    block's top in placing order (the first one reaching it gives up), 0, negative, huge."""
    peak = inst.peak(offsets)
    tops = [offsets[i] + inst.size[i] for i in order]
    return [None, peak, peak + 1, max(peak - 1, 0), *tops[:: max(len(tops) // 8, 1)], 0, -5, 2**70]


def assert_same(inst: Instance, order: list[int]) -> int:
    """Native and Python best fit agree without and with every cut-off; returns how many
    comparisons gave up (None)."""
    python = best_fit_python(inst, order)
    assert python is not None
    assert native_fit(inst, order) == python
    gave_up = 0
    for limit in cut_offs(inst, order, python):
        expected = best_fit_python(inst, order, limit)
        assert native_fit(inst, order, limit) == expected, limit
        gave_up += expected is None
    return gave_up


def test_random_instances_sparse_to_dense_give_identical_offsets():
    gave_up = compared = 0
    for seed in range(60):
        rng = random.Random(seed)
        dense = (0.0, 0.3, 0.6, 0.9, 1.0)[seed % 5]
        sizes = ((1, 2, 3, 5, 8), (0, 1, 2, 7, 16))[seed % 2]
        inst = instance(seed, rng.randrange(1, 140), dense, sizes)
        for order in [o for _, o in orderings(inst)] + [rng.sample(range(inst.n), inst.n)]:
            assert native_fit(inst, order) == plain_best_fit(inst, order)
            gave_up += assert_same(inst, order)
            compared += 1
    assert compared > 300 and gave_up > 600  # the cut-offs were met, not only passed


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks=block_lists(40, 20, 10, 300, [1, 2, 16, 64], "c"), rank=st.randoms(use_true_random=False),
       dense=st.sampled_from([0.0, 0.5, 1.0]))
def test_small_instances_with_empty_blocks_give_identical_offsets(blocks, rank, dense):
    conflicts: dict[str, set[str]] = {}
    for a in blocks:
        for b in blocks:
            if a.name < b.name and rank.random() < dense:
                conflicts.setdefault(a.name, set()).add(b.name)
                conflicts.setdefault(b.name, set()).add(a.name)
    inst = Instance.build(blocks, conflicts)
    order = list(range(inst.n))
    rank.shuffle(order)
    assert_same(inst, order)


def long_lived(count: int, seed: int, sizes: tuple[int, ...]) -> list[Block]:
    """``count`` blocks alive over most of 400 passes: nearly every pair overlaps."""
    rng = random.Random(seed)
    return [Block(f"b{i}", s, s + rng.randrange(300, 900), rng.choice(sizes) * 256, rng.choice([1, 256, 512]), "c")
            for i in range(count) for s in [rng.randrange(400)]]


@pytest.mark.parametrize("sizes", [(0, 1, 3, 8), (1, 3, 8)])
def test_neighbour_lists_of_large_dense_instances_give_identical_offsets(sizes):
    """From :data:`SWEEP_FROM` blocks there is no matrix: the dense scan tests neighbours
    by stamps, blocks with few neighbours sort theirs."""
    blocks = long_lived(SWEEP_FROM + 60, 1, sizes)
    inst = Instance.build(blocks, symmetric_conflicts([b.name for b in blocks], 200, 2))
    assert inst.adjacency is None and 4 * inst.pair_count >= inst.n**2
    order = next(orderings(inst))[1]
    python = best_fit_python(inst, order)
    assert native_fit(inst, order) == python
    peak = inst.peak(python)
    for limit in (peak, peak + 1):
        assert native_fit(inst, order, limit) == best_fit_python(inst, order, limit)


def test_neighbour_lists_of_large_sparse_instances_give_identical_offsets():
    inst = Instance.build([b for b in random_blocks(4000, 3) if b.memory_class == "device_local_optimal"])
    assert inst.adjacency is None
    for _, order in list(orderings(inst))[:3]:
        assert_same(inst, order)


@pytest.mark.skipif(not TRACES.is_dir(), reason="MiniMalloc traces not present (RGRAPH_SHARED)")
def test_minimalloc_traces_give_identical_offsets():
    traces = sorted(TRACES.glob("*.csv"))
    assert traces
    for path in traces:
        inst = Instance.build(read_trace(path))
        for _, order in orderings(inst):
            assert_same(inst, order)


def test_the_give_up_is_checked_on_every_block_top():
    """Against a mutant giving up only above ``give_up_at`` (or never): at the peak both give
    up, one byte above it neither does."""
    inst = instance(3, 80, 0.9)
    for _, order in orderings(inst):
        offsets = native_fit(inst, order)
        peak = inst.peak(offsets)
        assert offsets == best_fit_python(inst, order)
        assert native_fit(inst, order, peak) is None
        assert native_fit(inst, order, peak + 1) == offsets
        first = order[0]
        assert native_fit(inst, order, inst.size[first]) is None  # the first block's top
        assert native_fit(inst, order, 0) is None


def test_partial_orders_leave_the_other_blocks_unplaced():
    inst = instance(5, 50, 0.6, (0, 1, 2, 7, 16))
    order = list(range(0, inst.n, 3))
    assert native_fit(inst, order) == best_fit_python(inst, order)
    assert native_fit(inst, []) == [-1] * inst.n


def test_bad_orders_are_refused_not_crashed():
    inst = instance(1, 10, 0.5)
    for order in ([0, 10], [1, 1], [-1]):
        with pytest.raises(ValueError):
            native_fit(inst, order)


def test_sizes_past_62_bits_run_the_python_code():
    blocks = [Block(f"b{i}", i, i + 3, 2**61 + i, 1, "c") for i in range(12)]
    inst = Instance.build(blocks)
    assert native_flat(NATIVE, inst) is None and inst.accelerated["fit"] is False
    order = next(orderings(inst))[1]
    assert greedy.best_fit(inst, order) == plain_best_fit(inst, order)


def test_the_flat_copy_is_made_once_per_instance():
    inst = instance(2, 30, 0.9)
    flat = native_flat(NATIVE, inst)
    assert native_flat(NATIVE, inst) is flat and inst.accelerated["fit"] is flat


def random_conflicts(rng: random.Random, names: list[str], share: float) -> dict[str, set[str]]:
    """Any pairs, one-way ones, a block with itself and names of no block included."""
    conflicts: dict[str, set[str]] = {"elsewhere": {names[0], "nowhere"}} if names else {}
    for a in names:
        for b in names:
            if rng.random() < share:
                conflicts.setdefault(a, set()).add(b)
    return conflicts


def test_conflict_matrix_is_the_python_one():
    separable = 0
    for seed in range(150):
        rng = random.Random(seed)
        blocks = [Block(f"b{i}", s, s + rng.randrange(12), 256, 1, "c") for i in range(rng.randrange(0, 90))
                  for s in [rng.randrange(40)]]
        conflicts = random_conflicts(rng, [b.name for b in blocks], rng.choice([0.0, 0.01, 0.2, 1.0]))
        start, end = [b.start for b in blocks], [b.end for b in blocks]
        matrix, together = NATIVE.conflict_matrix(start, end, [b.name for b in blocks], conflicts)
        expected, rows, expected_together = instance_module._conflict_graph(blocks, start, end, conflicts)
        assert rows is None and together == expected_together
        assert matrix.dtype == expected.dtype and matrix.shape == expected.shape
        assert np.array_equal(matrix, expected)
        separable += together
    assert 10 < separable < 140


def test_times_past_64_bits_fail_alike_compiled_or_not(monkeypatch):
    """Lifetimes past 63 bits are beyond numpy's int64 (the Python code's limit too): the
    compiled matrix hands them to the Python code, which refuses them the same way."""
    blocks = [Block("a", 0, 2**70, 16, 4, "c"), Block("b", 5, 2**70 + 1, 8, 4, "c"), Block("c", 2**71, 2**71, 8, 4, "c")]
    with pytest.raises(OverflowError):
        Instance.build(blocks, {"a": {"c"}, "c": {"a"}})
    monkeypatch.setattr(instance_module, "_NATIVE", None)
    with pytest.raises(OverflowError):
        Instance.build(blocks, {"a": {"c"}, "c": {"a"}})


def test_clique_growth_is_the_python_one(monkeypatch):
    compared = 0
    for seed in range(200):
        rng = random.Random(seed)
        inst = instance(seed, rng.randrange(1, 100), rng.choice([0.05, 0.3, 0.9, 1.0]), (0, 1, 2, 7, 16))
        if inst.separable:
            continue
        compiled = bounds.clique_bound(inst)
        monkeypatch.setattr(greedy, "NATIVE", None)
        assert bounds.clique_bound(inst) == compiled
        monkeypatch.setattr(greedy, "NATIVE", NATIVE)
        members = [0, inst.n - 1]
        assert NATIVE.clique_extra(native_flat(NATIVE, inst), members) == bounds._clique_extra(inst, members)
        compared += 1
    assert compared > 150


def without_native(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(greedy, "NATIVE", None)
    monkeypatch.setattr(instance_module, "_NATIVE", None)


def test_place_is_the_same_without_the_compiled_fit(monkeypatch):
    for seed in range(6):
        blocks = random_blocks(300, seed)
        rng = random.Random(seed)
        conflicts = random_conflicts(rng, [b.name for b in blocks], 0.002)
        compiled = [place(blocks, "aliased", conflicts=c) for c in (None, conflicts)]
        cls = Instance.build([b for b in blocks if b.memory_class == "device_local_optimal"], conflicts)
        compiled_class = place_class(cls, 0.05)
        without_native(monkeypatch)
        python = [place(blocks, "aliased", conflicts=c) for c in (None, conflicts)]
        python_class = place_class(Instance.build(cls.blocks, conflicts), 0.05)
        monkeypatch.undo()
        for a, b in zip(compiled, python, strict=True):
            assert (a.offsets, a.heaps, a.stats.peak_bytes, a.stats.lower_bound_bytes) == (
                b.offsets, b.heaps, b.stats.peak_bytes, b.stats.lower_bound_bytes)
        assert (compiled_class.offsets, compiled_class.how, compiled_class.proven) == (
            python_class.offsets, python_class.how, python_class.proven)


def test_plans_are_the_same_without_the_compiled_fit(monkeypatch):
    """A random graph with cross-queue conflicts (classes not separable: greedy only)."""
    from rgraph.compiler.pipeline import compile_plan, frontend
    from rgraph.plan import dump
    from rgraph.random_graph import random_graph, to_yaml

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "g.yaml"
        path.write_text(to_yaml(random_graph(seed=300, passes=300)))
        spec = frontend(path, size=(16, 16)).spec
        compiled = dump(compile_plan(spec, policy="aliased"))
        without_native(monkeypatch)
        assert dump(compile_plan(spec, policy="aliased")) == compiled
