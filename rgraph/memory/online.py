"""Online policies: allocate in schedule order and free after each block's last pass, as a
general-purpose allocator would, without knowing the future."""

from __future__ import annotations

from collections.abc import Sequence

from rgraph.memory.model import Block
from rgraph.memory.tlsf import Tlsf


def schedule_events(blocks: Sequence[Block]) -> list[tuple[int, int, int]]:
    """(time, kind, index) events: at each pass, frees (kind 0) of blocks whose last pass
    was the one before, then allocations (kind 1) of blocks starting there, in input order."""
    events = [(b.end + 1, 0, i) for i, b in enumerate(blocks)]
    events += [(b.start, 1, i) for i, b in enumerate(blocks)]
    events.sort()
    return events


def place_tlsf(blocks: Sequence[Block]) -> tuple[list[int], int]:
    """One growable TLSF heap: offsets and the heap's high-water mark."""
    heap = Tlsf(growable=True)
    offsets = [0] * len(blocks)
    for _, kind, i in schedule_events(blocks):
        if kind == 1:
            offsets[i] = heap.allocate(blocks[i].aligned_size, blocks[i].alignment)  # type: ignore[assignment]
        else:
            heap.free(offsets[i])
    return offsets, heap.size


def place_blocks(blocks: Sequence[Block], block_bytes: int) -> tuple[list[tuple[int, int]], list[int]]:
    """VMA-like fixed-size blocks: each resource goes into the first block with room (TLSF
    inside each block), a new block when none has room; a resource larger than half a block
    gets a dedicated allocation. Returns (allocation index, offset) per block and the byte
    size of each allocation in creation order. Blocks are never released (peak = all)."""
    pools: list[Tlsf | None] = []  # None marks a dedicated allocation
    sizes: list[int] = []
    where: list[tuple[int, int]] = [(0, 0)] * len(blocks)
    for _, kind, i in schedule_events(blocks):
        b = blocks[i]
        if kind == 0:
            pool = pools[where[i][0]]
            if pool is not None:
                pool.free(where[i][1])
            continue
        size = b.aligned_size
        if size > block_bytes // 2:
            pools.append(None)
            sizes.append(size)
            where[i] = (len(pools) - 1, 0)
            continue
        for k, pool in enumerate(pools):
            if pool is not None:
                offset = pool.allocate(size, b.alignment)
                if offset is not None:
                    where[i] = (k, offset)
                    break
        else:
            pool = Tlsf(block_bytes)
            offset = pool.allocate(size, b.alignment)
            if offset is None:  # alignment padding too large for a block: go dedicated
                pool, offset = None, 0
            pools.append(pool)
            sizes.append(block_bytes if pool is not None else size)
            where[i] = (len(pools) - 1, offset)
    return where, sizes
