"""Cells -> mip x layer rectangles (the sync phase's barrier rectangles, naive sync's)."""

from __future__ import annotations

from collections.abc import Iterable


def mip_layer_rectangles(cells: Iterable[tuple[int, int]]) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """(mip, layer) cells -> disjoint half-open (mips, layers) rectangles: runs of layers per
    mip, with consecutive mips of equal runs merged; sorted by mips, then layers."""
    rows: list[tuple[int, list[tuple[int, int]]]] = []  # (mip, its runs of layers), by mip
    runs: list[tuple[int, int]] = []
    mip = None
    for m, layer in sorted(cells):
        if m != mip:
            mip = m
            runs = [(layer, layer + 1)]
            rows.append((m, runs))
        elif runs[-1][1] == layer:
            runs[-1] = (runs[-1][0], layer + 1)
        else:
            runs.append((layer, layer + 1))
    if len(rows) == 1:
        m, runs = rows[0]
        return [((m, m + 1), run) for run in runs]
    out = []
    start, count = 0, len(rows)
    while start < count:
        first, runs = rows[start]
        end = start
        while end + 1 < count and rows[end + 1][0] == rows[end][0] + 1 and rows[end + 1][1] == runs:
            end += 1
        mips = (first, rows[end][0] + 1)
        out += [(mips, run) for run in runs]
        start = end + 1
    return out
