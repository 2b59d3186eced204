"""The dependency graph of passes: a networkx DiGraph with one edge per hazard kind.

Nodes are pass names (attribute ``order``: declaration order). An edge ``u -> v`` carries
``kinds`` (subset of RAW, WAR, WAW) and ``resources``. Dependencies are found per
subresource cell (resource, mip, layer), like SSA renaming of each cell.
"""

from __future__ import annotations

from collections.abc import Iterable

import networkx as nx

from rgraph.spec.specialize import AccessSpec, PassSpec

READ_WRITE_USAGES = frozenset({"color_attachment_blend", "depth_attachment", "storage_rw"})

Cell = tuple[str, int, int]


def reads(access: AccessSpec) -> bool:
    return not access.write or access.usage in READ_WRITE_USAGES


Edges = dict[tuple[str, str], tuple[set[str], set[str]]]  # (u, v) -> (kinds, resources)


def dependencies(passes: Iterable[PassSpec]) -> Edges:
    """RAW, WAR and WAW dependencies between passes, in declaration (program) order."""
    edges: Edges = {}
    last_writer: dict[Cell, str] = {}
    readers: dict[Cell, list[str]] = {}

    def add(u: str, v: str, kind: str, resource: str) -> None:
        if u == v:
            return
        entry = edges.get((u, v))
        if entry is None:
            edges[(u, v)] = ({kind}, {resource})
        else:
            entry[0].add(kind)
            entry[1].add(resource)

    for p in passes:
        for access in p.accesses:
            is_read = reads(access)
            for cell in access.cells:
                writer = last_writer.get(cell)
                if is_read and writer is not None:
                    add(writer, p.name, "RAW", access.resource)
                if access.write:
                    for reader in readers.get(cell, ()):
                        add(reader, p.name, "WAR", access.resource)
                    if writer is not None:
                        add(writer, p.name, "WAW", access.resource)
        for access in p.accesses:
            for cell in access.cells:
                if access.write:
                    last_writer[cell] = p.name
                    readers[cell] = []
                else:
                    readers.setdefault(cell, []).append(p.name)
    return edges


def build_graph(passes: Iterable[PassSpec]) -> nx.DiGraph:
    """The pass graph as a networkx DiGraph: edge attributes ``kinds`` and ``resources``."""
    passes = list(passes)
    graph = nx.DiGraph()
    graph.add_nodes_from((p.name, {"order": p.order}) for p in passes)
    graph.add_edges_from(
        (u, v, {"kinds": kinds, "resources": res}) for (u, v), (kinds, res) in dependencies(passes).items()
    )
    return graph


def raw_ancestors(edges: Edges, roots: Iterable[str]) -> set[str]:
    """``roots`` and every pass they reach backwards through read-after-write edges."""
    preds: dict[str, list[str]] = {}
    for (u, v), (kinds, _) in edges.items():
        if "RAW" in kinds:
            preds.setdefault(v, []).append(u)
    seen = set(roots)
    stack = list(seen)
    while stack:
        for u in preds.get(stack.pop(), ()):
            if u not in seen:
                seen.add(u)
                stack.append(u)
    return seen


def last_writers(passes: Iterable[PassSpec], resources: set[str]) -> set[str]:
    """Passes whose writes to ``resources`` survive to the end of the frame."""
    final: dict[Cell, str] = {}
    for p in passes:
        for access in p.accesses:
            if access.write and access.resource in resources:
                for cell in access.cells:
                    final[cell] = p.name
    return set(final.values())
