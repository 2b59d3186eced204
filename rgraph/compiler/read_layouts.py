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


def unify_read_layouts(
    passes: Sequence[PassSpec], resources: Mapping[str, ResourceSpec], syncs: list[list[Sync]]
) -> list[list[Sync]]:
    """``syncs`` (per pass, per access) with mixed-layout read groups moved to GENERAL (a new
    outer list; the inner lists of passes with a change are new too)."""
    candidates = {
        name for name, res in resources.items()
        if res.is_image and res.lifetime == "transient" and res.format is not None
        and not res.format.has_depth and not res.format.has_stencil
    }
    uses: dict[str, list[tuple[int, int, bool, str]]] = {}  # (pass, access, write, usage)
    excluded: set[str] = set()
    if candidates:
        for i, p in enumerate(passes):
            for j, a in enumerate(p.accesses):
                name = a.resource
                if name not in candidates or name in excluded:
                    continue  # other images are excluded (and buffers have no layout)
                res = resources[name]
                if a.mips != (0, res.mips) or a.layers != (0, res.layers):  # not the whole image
                    excluded.add(name)
                    continue
                entry = (i, j, a.write, a.usage)
                if name in uses:
                    uses[name].append(entry)
                else:
                    uses[name] = [entry]
    out = list(syncs)
    copied: set[int] = set()
    for name, seq in uses.items():
        if name in excluded:
            continue
        group: list[tuple[int, int]] = []  # the movable reads since the last write
        for i, j, write, usage in [*seq, (-1, -1, True, "")]:  # a sentinel closes the last group
            if not write:
                if usage in GENERAL_READS:
                    group.append((i, j))
                continue
            if len(group) > 1 and len({out[gi][gj].layout for gi, gj in group}) > 1:
                for gi, gj in group:
                    if gi not in copied:
                        out[gi] = list(out[gi])
                        copied.add(gi)
                    out[gi][gj] = replace(out[gi][gj], layout="GENERAL")
            group = []
    return out
