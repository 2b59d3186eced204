"""Pass dependencies derived from a plan's accesses, per subresource (mip, layer).

A read depends on the previous writer of each subresource it reads (RAW); a write on the
previous writer (WAW, or RAW when it also reads, e.g. ``depth_attachment``) and on the
readers since that write (WAR). Accesses of one pass see the state before the pass.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from rgraph.report.fmt import is_write, reads_too

Plan = dict[str, Any]
Cell = tuple[int, int] | None  # (mip, layer); None for a buffer (or a whole-resource access)

KIND_ORDER = ("RAW", "WAR", "WAW")


@dataclass(frozen=True)
class Edge:
    """``src`` must finish (as far as ``resources`` go) before ``dst``; indices are plan positions."""

    src: int
    dst: int
    kind: str  # RAW | WAR | WAW
    resources: tuple[str, ...]


@dataclass(frozen=True)
class SemaphoreEdge:
    src: int  # the pass that signals
    dst: int  # the pass that waits
    queue: str
    value: int


@dataclass
class _CellState:
    writer: int | None = None
    readers: set[int] = field(default_factory=set)


def _cells(sub: dict[str, Any] | None) -> Iterator[Cell]:
    if not sub:
        yield None
        return
    mips = sub.get("mips") or [0, 1]
    layers = sub.get("layers") or [0, 1]
    for mip in range(mips[0], mips[1]):
        for layer in range(layers[0], layers[1]):
            yield (mip, layer)


def dependency_edges(plan: Plan) -> list[Edge]:
    """RAW, WAR and WAW edges between executed passes, sorted by (src, dst, kind)."""
    state: dict[str, dict[Cell, _CellState]] = {}
    found: dict[tuple[int, int, str], set[str]] = {}

    def add(src: int | None, dst: int, kind: str, resource: str) -> None:
        if src is not None and src != dst:
            found.setdefault((src, dst, kind), set()).add(resource)

    for i, p in enumerate(plan["passes"]):
        accesses = p.get("accesses") or []
        for a in accesses:
            cells = state.setdefault(a["resource"], {})
            for cell in _cells(a.get("subresource")):
                st = cells.get(cell)
                if st is None:
                    continue
                if reads_too(a):
                    add(st.writer, i, "RAW", a["resource"])
                elif is_write(a):
                    add(st.writer, i, "WAW", a["resource"])
                if is_write(a):
                    for reader in st.readers:
                        add(reader, i, "WAR", a["resource"])
        for a in accesses:
            cells = state.setdefault(a["resource"], {})
            for cell in _cells(a.get("subresource")):
                st = cells.setdefault(cell, _CellState())
                if is_write(a):
                    st.writer, st.readers = i, set()
        for a in accesses:
            if is_write(a):
                continue
            cells = state[a["resource"]]
            for cell in _cells(a.get("subresource")):
                if cells[cell].writer != i:
                    cells[cell].readers.add(i)
    return [
        Edge(src, dst, kind, tuple(sorted(res)))
        for (src, dst, kind), res in sorted(found.items(), key=lambda kv: (kv[0][0], kv[0][1], KIND_ORDER.index(kv[0][2])))
    ]


def semaphore_edges(plan: Plan) -> list[SemaphoreEdge]:
    """Signal -> wait pairs: the pass signalling ``queue`` to ``value`` -> the pass waiting on it."""
    signaller: dict[tuple[str, int], int] = {}
    for i, p in enumerate(plan["passes"]):
        for s in p.get("signals") or []:
            signaller[(s["queue"], s["value"])] = i
    edges = []
    for i, p in enumerate(plan["passes"]):
        for w in p.get("waits") or []:
            # A timeline wait is satisfied by the signal of that value or, absent one, the next higher.
            candidates = [v for (q, v) in signaller if q == w["queue"] and v >= w["value"]]
            if candidates:
                value = min(candidates)
                edges.append(SemaphoreEdge(signaller[(w["queue"], value)], i, w["queue"], w["value"]))
    return sorted(edges, key=lambda e: (e.src, e.dst, e.queue, e.value))
