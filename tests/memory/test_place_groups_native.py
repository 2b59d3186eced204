"""``_fit.class_groups`` (``rgraph.memory.place``'s checks, classes, densities and bytes),
``_fit.class_arrays`` (``Instance.build``'s lists, sections and totals) and ``_fit.orderings``
(``greedy.orderings``' six orders) against their Python code, on random blocks and edge cases: none, one, zero sizes, identical lifetimes, times
past 62 bits, and blocks ``check_blocks`` rejects."""

from __future__ import annotations

import importlib
import random
from itertools import accumulate

import pytest

from rgraph.memory import class_groups_python, greedy, place
from rgraph.memory.instance import Instance, sections
from rgraph.memory.model import Block
from rgraph.memory.random_instances import random_blocks

try:  # straight from the build, whatever RGRAPH_NATIVE says
    NATIVE = importlib.import_module("rgraph.memory._fit")
except ImportError:
    NATIVE = None

pytestmark = pytest.mark.skipif(NATIVE is None, reason="rgraph.memory._fit not built (setup.py build_ext)")


def python_arrays(blocks: list[Block]) -> tuple:
    start, end = [b.start for b in blocks], [b.end for b in blocks]
    size, align = [b.aligned_size for b in blocks], [b.alignment for b in blocks]
    lo, hi, count = sections(start, end)
    diff = [0] * (count + 1)
    for a, b, z in zip(lo, hi, size, strict=True):
        diff[a] += z
        diff[b] -= z
    return start, end, size, align, lo, hi, count, tuple(accumulate(diff[:count]))


def cases() -> list[list[Block]]:
    out = [[], [Block("a", 3, 3, 0, 1, "x")],
           [Block("a", 0, 5, 100, 64, "x"), Block("b", 0, 5, 7, 8, "x"), Block("c", 0, 5, 0, 4, "y")],
           [Block(f"b{i}", i % 3, i % 3 + 1, 10 * i + 1, 1 << (i % 5), f"c{i % 2}") for i in range(20)],
           [Block("neg", -4, -1, 5, 2, "x"), Block("z", -1, 0, 5, 2, "x")]]
    out += [random_blocks(n, seed) for n, seed in ((50, 1), (300, 2), (1000, 3))]
    rng = random.Random(7)
    for _ in range(20):
        n = rng.randrange(1, 60)
        blocks = []
        for i in range(n):
            s = rng.randrange(10)
            blocks.append(Block(f"r{i}", s, s + rng.randrange(4), rng.randrange(0, 5000),
                                rng.choice([1, 2, 64, 256]), rng.choice(["p", "q", "r"])))
        out.append(blocks)
    return out


@pytest.mark.parametrize("blocks", cases())
def test_compiled_matches_python(blocks: list[Block]) -> None:
    assert NATIVE.class_groups(blocks) == class_groups_python(blocks)
    for group, *_ in class_groups_python(blocks).values():
        assert NATIVE.class_arrays(group) == python_arrays(group)
    assert NATIVE.class_arrays([]) == python_arrays([])


@pytest.mark.parametrize("bad", [
    [Block("a", 0, 1, 1, 1, "x"), Block("a", 2, 3, 1, 1, "x")],
    [Block("a", 2, 1, 1, 1, "x")],
    [Block("a", 0, 1, -1, 1, "x")],
    [Block("a", 0, 1, 1, 0, "x")],
])
def test_rejected_blocks_fall_back(bad: list[Block]) -> None:
    """Blocks ``check_blocks`` rejects: the compiled grouping declines, and ``place`` raises
    the same error as the Python code."""
    assert NATIVE.class_groups(bad) is None
    with pytest.raises(ValueError) as python:
        class_groups_python(bad)
    with pytest.raises(ValueError) as placed:
        place(bad)
    assert str(placed.value) == str(python.value)


def test_huge_values_decline() -> None:
    huge = [Block("a", 0, 1 << 62, 1, 1, "x"), Block("b", 0, 1, 1 << 70, 1, "x")]
    assert NATIVE.class_groups(huge) is None  # a time past 62 bits
    with pytest.raises(OverflowError):
        NATIVE.class_arrays(huge)
    big = [Block("b", 0, 1, 1 << 70, 1, "x"), Block("c", 1, 2, 3, 1, "x")]
    assert NATIVE.class_groups(big) == class_groups_python(big)  # sizes stay Python ints
    with pytest.raises(OverflowError):
        NATIVE.class_arrays(big)
    assert place(huge).offsets == place(huge).offsets


def numpy_orderings(inst: Instance) -> list[tuple[str, list[int]]]:
    """``greedy.orderings`` without the compiled sort: numpy's where keys fit, else Python's."""
    saved = greedy.NATIVE
    greedy.NATIVE = None
    try:
        return list(greedy.orderings(inst))
    finally:
        greedy.NATIVE = saved


@pytest.mark.parametrize("blocks", cases())
def test_orderings_match(blocks: list[Block]) -> None:
    """``_fit.orderings`` (merge sort, ties by index) gives numpy's stable lexsort orders and
    ``_orderings_python``'s, on groups with many equal keys (ties) and runs past 8 blocks."""
    for group, *_ in class_groups_python(blocks).values():
        inst = Instance.build(group)
        orders = NATIVE.orderings(inst.start, inst.end, inst.size, inst.sec_lo, inst.sec_hi, inst._totals)
        expected = numpy_orderings(inst)
        assert list(zip(greedy.ORDERINGS, orders, strict=True)) == expected
        assert list(greedy._orderings_python(inst)) == expected
        assert list(greedy.orderings(inst)) == expected


def test_orderings_overflow_falls_back() -> None:
    """An area past 62 bits: the compiled sort declines and ``orderings`` sorts in Python."""
    blocks = [Block("a", 0, 100, 1 << 60, 1, "x"), Block("b", 50, 60, 1 << 58, 1, "x"), Block("c", 3, 3, 1, 1, "x")]
    inst = Instance.build(blocks)
    with pytest.raises(OverflowError):
        NATIVE.orderings(inst.start, inst.end, inst.size, inst.sec_lo, inst.sec_hi, inst._totals)
    assert list(greedy.orderings(inst)) == list(greedy._orderings_python(inst))


@pytest.mark.parametrize("blocks", cases())
def test_peak_and_live_at_match(blocks: list[Block]) -> None:
    """``_fit.peak`` (``Instance.peak``) and ``_fit.live_at`` (``clique_bound``'s members)
    against the Python expressions, on best-fit offsets and every section."""
    from operator import add

    for group, *_ in class_groups_python(blocks).values():
        inst = Instance.build(group)
        for _, order in greedy.orderings(inst):
            offsets = greedy.best_fit_python(inst, order)
            assert offsets is not None
            assert NATIVE.peak(offsets, inst.size) == max(map(add, offsets, inst.size), default=0)
        for s in range(-1, inst.section_count + 1):
            assert NATIVE.live_at(inst.sec_lo, inst.sec_hi, s) == [
                i for i, (lo, hi) in enumerate(zip(inst.sec_lo, inst.sec_hi, strict=True)) if lo <= s < hi]
    assert NATIVE.peak([], []) == 0
    assert NATIVE.peak([-5, -9], [1, 2]) == -4  # no floor at 0 where every top is negative (as max)
    with pytest.raises(OverflowError):
        NATIVE.peak([1 << 63], [1])
    big = Instance.build([Block("a", 0, 1, 1 << 70, 1, "x")])
    assert big.peak([5]) == 5 + (1 << 70)  # the Python code, past 62 bits
