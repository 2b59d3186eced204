"""Pass schedules (``--schedule``): the order passes execute in, always a topological order
of the pass graph's RAW/WAR/WAW dependencies, so every schedule computes the same frame.

- ``declaration`` (default): declaration order minus culled passes.
- ``async-early``: passes on the compute and transfer queues as early as their dependencies
  allow (ties in declaration order), so async work is submitted before the graphics work it
  can overlap with.
"""

from __future__ import annotations

from collections.abc import Sequence

import networkx as nx

from rgraph.defaults import DEFAULT_SCHEDULE, SCHEDULES
from rgraph.errors import RGraphError
from rgraph.ir.graph import build_graph
from rgraph.spec.specialize import PassSpec

__all__ = ["DEFAULT_SCHEDULE", "SCHEDULES", "schedule_passes"]


def schedule_passes(passes: Sequence[PassSpec], mode: str = DEFAULT_SCHEDULE) -> list[PassSpec]:
    """``passes`` (in declaration order) in the order schedule ``mode`` executes them."""
    if mode not in SCHEDULES:
        raise RGraphError.in_file("<command line>", f"--schedule expects one of {', '.join(SCHEDULES)}, got '{mode}'")
    if mode == "declaration":
        return list(passes)
    by_name = {p.name: p for p in passes}

    def key(name: str) -> tuple[int, int]:
        p = by_name[name]
        return (0 if p.queue != "graphics" else 1, p.order)

    return [by_name[n] for n in nx.lexicographical_topological_sort(build_graph(passes), key=key)]
