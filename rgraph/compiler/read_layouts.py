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

# Not transfer_src: copies from GENERAL draw a validation performance warning (the layer
# wants TRANSFER_SRC_OPTIMAL), so a copy keeps its own layout and transition.
GENERAL_READS = frozenset({"sampled", "storage_read"})


def to_general(groups: Mapping[str, Sequence[tuple[int, int, bool, str, str | None]]]) -> list[tuple[int, int]]:
    """(pass, access) of the reads to move to GENERAL: the movable reads of each group between
    two writes whose layouts differ. ``groups``: per candidate image (transient, colour, every
    access covering the whole image; ``rgraph.compiler.trace``), its (pass, access, write,
    usage, layout) in executed order."""
    out = []
    for seq in groups.values():
        group: list[tuple[int, int]] = []  # the movable reads since the last write
        layouts: set[str | None] = set()
        for i, j, write, usage, layout in [*seq, (-1, -1, True, "", None)]:  # a sentinel closes the last group
            if not write:
                if usage in GENERAL_READS:
                    group.append((i, j))
                    layouts.add(layout)
                continue
            if len(group) > 1 and len(layouts) > 1:
                out += group
            group = []
            layouts = set()
    return out
