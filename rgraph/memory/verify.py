"""Independent check of a placement: no two live blocks share bytes, offsets are aligned,
every block lies inside its heap and its heap has the block's memory class."""

from __future__ import annotations

from collections.abc import Sequence

from rgraph.memory.model import Block, Placement


def overlaps(blocks: Sequence[Block], placement: Placement) -> list[str]:
    """Every violation found, as readable sentences (empty when the placement is sound)."""
    problems: list[str] = []
    heaps = {h.id: h for h in placement.heaps}
    if len(heaps) != len(placement.heaps):
        problems.append("duplicate heap ids")
    per_heap: dict[int, list[tuple[Block, int]]] = {}
    for b in blocks:
        where = placement.offsets.get(b.name)
        if where is None:
            problems.append(f"{b.name}: not placed")
            continue
        heap_id, offset = where
        heap = heaps.get(heap_id)
        if heap is None:
            problems.append(f"{b.name}: heap {heap_id} does not exist")
            continue
        if heap.memory_class != b.memory_class:
            problems.append(f"{b.name}: class {b.memory_class} placed in heap {heap_id} of class {heap.memory_class}")
        if offset < 0 or offset % b.alignment:
            problems.append(f"{b.name}: offset {offset} is not a multiple of alignment {b.alignment}")
        if offset + b.size > heap.bytes:
            problems.append(f"{b.name}: [{offset}, {offset + b.size}) exceeds heap {heap_id} of {heap.bytes} bytes")
        per_heap.setdefault(heap_id, []).append((b, offset))
    for heap_id, placed in per_heap.items():
        placed.sort(key=lambda item: (item[0].start, item[0].name))
        for k, (a, off_a) in enumerate(placed):
            for b, off_b in placed[k + 1 :]:
                if b.start > a.end:
                    break
                if a.size and b.size and off_a < off_b + b.size and off_b < off_a + a.size:
                    problems.append(
                        f"{a.name} [{off_a}, {off_a + a.size}) passes {a.start}-{a.end} and "
                        f"{b.name} [{off_b}, {off_b + b.size}) passes {b.start}-{b.end} "
                        f"share bytes in heap {heap_id}"
                    )
    return problems
