"""Cells -> mip x layer rectangles (the sync phase's barrier rectangles, naive sync's)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable


def mip_layer_rectangles(cells: Iterable[tuple[int, int]]) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """(mip, layer) cells -> disjoint half-open (mips, layers) rectangles: runs of layers per
    mip, with consecutive mips of equal runs merged."""
    by_mip: dict[int, list[int]] = defaultdict(list)
    for mip, layer in cells:
        by_mip[mip].append(layer)
    runs_by_mip = {m: _runs(sorted(ls)) for m, ls in by_mip.items()}
    mips = sorted(runs_by_mip)
    out = []
    start = 0
    while start < len(mips):
        end = start
        while (
            end + 1 < len(mips)
            and mips[end + 1] == mips[end] + 1
            and runs_by_mip[mips[end + 1]] == runs_by_mip[mips[start]]
        ):
            end += 1
        out += [((mips[start], mips[end] + 1), run) for run in runs_by_mip[mips[start]]]
        start = end + 1
    return out


def _runs(values: list[int]) -> list[tuple[int, int]]:
    runs: list[tuple[int, int]] = []
    for v in values:
        if runs and runs[-1][1] == v:
            runs[-1] = (runs[-1][0], v + 1)
        else:
            runs.append((v, v + 1))
    return runs
