"""``rgraph.memory.place`` on ``_fit.Columns`` (each class's greedy on C arrays) against
``place`` on the same blocks as a list: the same offsets (in the same order), heaps and
stats, under every policy, with and without cross-queue conflicts, where a class needs the
search or TLSF (then placed from its blocks), and where the columns are not valid (blocks
``check_blocks`` rejects, values past 62 bits)."""

from __future__ import annotations

import importlib
import random

import pytest

import rgraph.memory as memory
from rgraph.memory import place
from rgraph.memory.model import Block, Placement
from rgraph.memory.random_instances import random_blocks

try:  # straight from the build, whatever RGRAPH_NATIVE says
    NATIVE = importlib.import_module("rgraph.memory._fit")
except ImportError:
    NATIVE = None

pytestmark = pytest.mark.skipif(NATIVE is None, reason="rgraph.memory._fit not built (setup.py build_ext)")


def columns(blocks: list[Block]) -> object:
    assert NATIVE is not None
    return NATIVE.Columns([b.name for b in blocks], [b.start for b in blocks], [b.end for b in blocks],
                          [b.size for b in blocks], [b.alignment for b in blocks], [b.memory_class for b in blocks])


def summary(p: Placement) -> tuple:
    s = p.stats
    return list(p.offsets.items()), p.heaps, (s.policy, s.peak_bytes, s.lower_bound_bytes, s.unaliased_bytes,
                                               s.allocations)


def random_conflicts(blocks: list[Block], seed: int, count: int) -> dict[str, set[str]]:
    rng = random.Random(seed)
    out: dict[str, set[str]] = {}
    for _ in range(count):
        a, b = rng.sample(blocks, 2)
        out.setdefault(a.name, set()).add(b.name)
        out.setdefault(b.name, set()).add(a.name)
    out.setdefault(blocks[0].name, set()).add("elsewhere")  # a name of no block: skipped
    return out


@pytest.mark.parametrize("policy", ["aliased", "optimal", "tlsf", "dedicated", "blocks:64MiB"])
def test_columns_place_as_blocks(policy: str, monkeypatch: pytest.MonkeyPatch) -> None:
    searched = []
    real = memory.place_class

    def counted(inst, *args, **kwargs):  # type: ignore[no-untyped-def]
        searched.append(inst.n)
        return real(inst, *args, **kwargs)

    monkeypatch.setattr(memory, "place_class", counted)
    fast = 0
    for seed in range(40):
        blocks = random_blocks(5 + seed * 4, seed)
        for conflicts in (None, random_conflicts(blocks, seed, seed % 7 * 3)):
            budget = 0.002 if policy == "optimal" else memory.DEFAULT_BUDGET_S  # optimal: 10 s by default
            expected = place(blocks, policy, time_budget_s=budget, conflicts=conflicts)
            before = len(searched)
            got = place(columns(blocks), policy, time_budget_s=budget, conflicts=conflicts)
            assert summary(got) == summary(expected), (seed, policy)
            fast += len(got.heaps) - (len(searched) - before)
    if policy in ("aliased", "optimal"):
        assert fast > 0 and searched  # classes placed on the arrays, and some by the search


def test_columns_too_dense_class_goes_to_tlsf() -> None:
    blocks = [Block(f"b{i}", 0, 10, 256 * (1 + i % 5), 256, "c") for i in range(480)]  # 229,920 pairs
    blocks += [Block(f"s{i}", i, i + 1, 512, 256, "d") for i in range(20)]
    assert summary(place(columns(blocks))) == summary(place(blocks))


@pytest.mark.parametrize("blocks", [
    [Block("a", 0, 1, 10, 8, "x"), Block("a", 2, 3, 10, 8, "x")],  # duplicate name
    [Block("a", 3, 1, 10, 8, "x")],  # start after end
    [Block("a", 0, 1, -1, 8, "x")],  # negative size
    [Block("a", 0, 1, 10, 0, "x")],  # alignment below 1
])
def test_invalid_columns_raise_as_blocks(blocks: list[Block]) -> None:
    cols = columns(blocks)
    assert not cols.valid
    with pytest.raises(ValueError) as expected:
        place(blocks)
    with pytest.raises(ValueError) as got:
        place(cols)
    assert str(got.value) == str(expected.value)


def test_columns_past_62_bits_place_as_blocks() -> None:
    blocks = [Block("a", 0, 3, 1 << 61, 1, "x"), Block("b", 2, 5, 1 << 61, 1, "x"), Block("c", 6, 7, 5, 1, "x")]
    cols = columns(blocks)
    assert not cols.valid
    assert summary(place(cols)) == summary(place(blocks))


def test_columns_are_a_sequence_of_blocks() -> None:
    blocks = random_blocks(12, 3)
    cols = columns(blocks)
    assert len(cols) == 12 and list(cols) == blocks and cols[5] == blocks[5]
    assert cols.classes == sorted({b.memory_class for b in blocks})
    for k, cls in enumerate(cols.classes):
        assert cols.group(k) == [b for b in blocks if b.memory_class == cls]
