"""Layout choice for groups of reads: one layout where several would need transitions.

Between two writes of an image, reads in different layouts (``sampled`` in
SHADER_READ_ONLY_OPTIMAL, then ``storage_read`` in GENERAL) each need a layout transition,
and a transition is a write, so the reads are serialized by an extra barrier. GENERAL
serves both usages, so such a group reads in GENERAL throughout: the first read's barrier
(needed anyway after the write) covers the whole group.

Applied conservatively: transient colour images whose every access covers the whole image
(no subresource selectors), so a group is the same for every mip and layer and never
continues into the next frame.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

from rgraph.compiler.usages import Sync
from rgraph.spec.specialize import PassSpec, ResourceSpec

# Not transfer_src: copies from GENERAL draw a validation performance warning (the layer
# wants TRANSFER_SRC_OPTIMAL), so a copy keeps its own layout and transition.
GENERAL_READS = frozenset({"sampled", "storage_read"})


def _whole(a, res: ResourceSpec) -> bool:
    return a.mips == (0, res.mips) and a.layers == (0, res.layers)


def unify_read_layouts(
    passes: Sequence[PassSpec], resources: Mapping[str, ResourceSpec], syncs: list[list[Sync]]
) -> list[list[Sync]]:
    """``syncs`` (per pass, per access) with mixed-layout read groups moved to GENERAL."""
    uses: dict[str, list[tuple[int, int]]] = {}
    excluded: set[str] = set()
    for i, p in enumerate(passes):
        for j, a in enumerate(p.accesses):
            res = resources[a.resource]
            if not res.is_image:
                continue  # buffers have no layout
            fmt = res.format
            if (res.lifetime != "transient" or fmt is None or fmt.has_depth
                    or fmt.has_stencil or not _whole(a, res)):
                excluded.add(a.resource)
            uses.setdefault(a.resource, []).append((i, j))
    out = [list(s) for s in syncs]
    for name, seq in uses.items():
        if name in excluded:
            continue
        group: list[tuple[int, int]] = []
        for i, j in [*seq, (-1, -1)]:  # a sentinel closes the last group
            a = passes[i].accesses[j] if i >= 0 else None
            if a is not None and not a.write:
                group.append((i, j))
                continue
            movable = [(gi, gj) for gi, gj in group if passes[gi].accesses[gj].usage in GENERAL_READS]
            if len({out[gi][gj].layout for gi, gj in movable}) > 1:
                for gi, gj in movable:
                    out[gi][gj] = replace(out[gi][gj], layout="GENERAL")
            group = []
    return out
