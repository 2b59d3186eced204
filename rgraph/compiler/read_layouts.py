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

from rgraph.compiler.usages import Sync
from rgraph.spec.specialize import ResourceSpec

# Not transfer_src: copies from GENERAL draw a validation performance warning (the layer
# wants TRANSFER_SRC_OPTIMAL), so a copy keeps its own layout and transition.
GENERAL_READS = frozenset({"sampled", "storage_read"})


class ReadGroups:
    """The accesses whose read layouts may be unified (mixed-layout read groups move to GENERAL),
    noted one by one in executed order (``rgraph.compiler.sync_inputs``)."""

    def __init__(self, resources: Mapping[str, ResourceSpec]) -> None:
        self.resources = resources
        self.candidates = {
            name for name, res in resources.items()
            if res.is_image and res.lifetime == "transient" and res.format is not None
            and not res.format.has_depth and not res.format.has_stencil
        }
        self.uses: dict[str, list[tuple[int, int, bool, str]]] = {}  # (pass, access, write, usage)
        self.excluded: set[str] = set()

    def note(self, i: int, j: int, a) -> None:
        """Access ``j`` of pass ``i`` (call only for a resource in ``candidates``)."""
        name = a.resource
        if name in self.excluded:
            return
        res = self.resources[name]
        if a.mips != (0, res.mips) or a.layers != (0, res.layers):  # not the whole image
            self.excluded.add(name)
            return
        entry = (i, j, a.write, a.usage)
        if name in self.uses:
            self.uses[name].append(entry)
        else:
            self.uses[name] = [entry]

    def to_general(self, syncs: Sequence[Sequence[Sync]]) -> list[tuple[int, int]]:
        """(pass, access) of the reads to move to GENERAL: the movable reads of each group
        between two writes whose layouts differ."""
        out = []
        for name, seq in self.uses.items():
            if name in self.excluded:
                continue
            group: list[tuple[int, int]] = []  # the movable reads since the last write
            for i, j, write, usage in [*seq, (-1, -1, True, "")]:  # a sentinel closes the last group
                if not write:
                    if usage in GENERAL_READS:
                        group.append((i, j))
                    continue
                if len(group) > 1 and len({syncs[gi][gj].layout for gi, gj in group}) > 1:
                    out += group
                group = []
        return out
