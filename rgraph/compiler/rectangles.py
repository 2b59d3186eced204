"""Cells with one barrier -> mip x layer rectangles (one ``Barrier`` each, in a fixed order)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Sequence
from operator import itemgetter

from rgraph.compiler.sync_types import Barrier, BarrierKey
from rgraph.ir.graph import Cell

#: (resource, mips, layers): barriers of one pass never share all three (their cells are disjoint)
BARRIER_ORDER = itemgetter(0, 1, 2)
_new = tuple.__new__  # cheaper than a named tuple's Python-level ``__new__``


def barriers_of(found: Sequence[tuple[Cell, BarrierKey, int | None]]) -> list[Barrier]:
    """One pass's (cell, key, release pass) triples -> its barriers: cells of one resource with
    equal key and release pass merged into rectangles, sorted by (resource, mips, layers)."""
    if len(found) == 1:
        (res, mip, layer), key, _ = found[0]
        return [_new(Barrier, (res, (mip, mip + 1), (layer, layer + 1), key))]
    by_res: dict[str, list[tuple[Cell, BarrierKey, int | None]]] = {}
    for item in found:
        res = item[0][0]
        if res in by_res:
            by_res[res].append(item)
        else:
            by_res[res] = [item]
    out = []
    for res, items in by_res.items():
        if len(items) == 1:  # one cell (every buffer): its own rectangle
            (_, mip, layer), key, _ = items[0]
            out.append(_new(Barrier, (res, (mip, mip + 1), (layer, layer + 1), key)))
            continue
        groups: dict[tuple[BarrierKey, int | None], list[Cell]] = {}
        for c, key, release_at in items:
            groups.setdefault((key, release_at), []).append(c)
        for (key, _), cs in groups.items():
            out += rectangles(res, key, cs)
    out.sort(key=BARRIER_ORDER)
    return out


def rectangles(res: str, key: BarrierKey, cells: Sequence[Cell]) -> list[Barrier]:
    """The barriers of ``cells`` (all of ``res``, one key), sorted by mips then layers."""
    if len(cells) == 1:
        _, mip, layer = cells[0]
        return [_new(Barrier, (res, (mip, mip + 1), (layer, layer + 1), key))]
    out = [Barrier(res, mips, layers, key) for mips, layers in mip_layer_rectangles((m, la) for _, m, la in cells)]
    out.sort(key=BARRIER_ORDER)
    return out


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
