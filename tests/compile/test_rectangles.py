"""``rgraph.compiler.rectangles.mip_layer_rectangles``: cells -> disjoint rectangles that cover
exactly the cells, in (mips, layers) order, each mip's layers in maximal runs and consecutive
mips with equal runs merged (the sync phase's barrier rectangles, naive sync's)."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from rgraph.compiler.rectangles import mip_layer_rectangles

CELLS = st.sets(st.tuples(st.integers(0, 5), st.integers(0, 7)), min_size=1, max_size=48)


def _runs(layers: list[int]) -> list[tuple[int, int]]:
    """Maximal runs of consecutive layers."""
    runs: list[tuple[int, int]] = []
    for layer in sorted(layers):
        if runs and runs[-1][1] == layer:
            runs[-1] = (runs[-1][0], layer + 1)
        else:
            runs.append((layer, layer + 1))
    return runs


@given(CELLS)
def test_rectangles_cover_the_cells_exactly_once(cells: set[tuple[int, int]]) -> None:
    rects = mip_layer_rectangles(list(cells))
    covered = [(m, la) for (m0, m1), (l0, l1) in rects for m in range(m0, m1) for la in range(l0, l1)]
    assert sorted(covered) == sorted(cells)
    assert rects == sorted(rects)


@given(CELLS)
def test_rectangles_merge_runs_and_equal_consecutive_mips(cells: set[tuple[int, int]]) -> None:
    rects = mip_layer_rectangles(list(cells))
    by_mip = {m: _runs([la for mm, la in cells if mm == m]) for m in {m for m, _ in cells}}
    # each rectangle's layer range is one of the maximal runs of each of its mips
    for (m0, m1), layers in rects:
        assert all(layers in by_mip[m] for m in range(m0, m1))
    # a rectangle's mips are not extendable: the next mip has other runs (or no cells)
    for (m0, m1), _ in rects:
        assert by_mip.get(m1) != by_mip[m0]
        assert m0 == 0 or by_mip.get(m0 - 1) != by_mip[m0]


def test_one_cell_and_a_full_image() -> None:
    assert mip_layer_rectangles([(2, 3)]) == [((2, 3), (3, 4))]
    assert mip_layer_rectangles([(m, la) for m in range(3) for la in range(2)]) == [((0, 3), (0, 2))]
    assert mip_layer_rectangles([(0, 0), (0, 1), (1, 0)]) == [((0, 1), (0, 2)), ((1, 2), (0, 1))]
