"""The mesh-buffer suballocator's placement logic (rgraph.vk.mesh_pool.SubAllocator), without Vulkan.

The backend below only hands out numbered memory objects and records frees: the placement
decisions (blocks, offsets, dedicated allocations, limits) are the code under test.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rgraph.vk.mesh_pool import AllocationLimitError, SubAllocator, choose_memory_type

MIB = 1 << 20


class CountingBackend:
    """Numbered fake memory objects; remembers sizes, types and frees."""

    def __init__(self) -> None:
        self.made: list[tuple[int, int]] = []  # (type_index, size)
        self.freed: list[int] = []

    def allocate(self, type_index: int, size: int) -> int:
        self.made.append((type_index, size))
        return len(self.made) - 1

    def free(self, block) -> None:
        self.freed.append(block.handle)


def assert_disjoint(allocs, block_size):
    """No two live allocations of one memory object share a byte; all inside their block."""
    by_block: dict[int, list] = {}
    for a in allocs:
        by_block.setdefault(id(a.block), []).append(a)
    for group in by_block.values():
        group.sort(key=lambda a: a.offset)
        for a in group:
            assert 0 <= a.offset and a.offset + a.size <= a.block.size
        for a, b in zip(group, group[1:], strict=False):
            assert a.offset + a.size <= b.offset, (a, b)


def test_alignment_and_no_overlap_in_one_block():
    sub = SubAllocator(4 * MIB, CountingBackend())
    requests = [(3200, 16), (4800, 64), (100, 256), (12345, 4096), (7, 1), (999, 32)] * 20
    allocs = [sub.allocate(size, align, 0) for size, align in requests]
    for a, (size, align) in zip(allocs, requests, strict=True):
        assert a.offset % align == 0
        assert a.size == size
    assert sub.stats.allocations == sub.stats.blocks == 1
    assert_disjoint(allocs, 4 * MIB)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 3 * MIB), st.sampled_from([1, 4, 16, 64, 256, 4096, 65536]),
                          st.integers(0, 2), st.booleans()), min_size=1, max_size=80),
       st.sampled_from([0, 1, 4]))
def test_random_requests_stay_aligned_disjoint_and_counted(requests, block_mib):
    backend = CountingBackend()
    block = block_mib * MIB
    sub = SubAllocator(block, backend)
    live = []
    for size, align, type_index, free_one in requests:
        a = sub.allocate(size, align, type_index)
        assert a.offset % align == 0
        assert a.block.type_index == type_index
        if block == 0 or size > block // 2:
            assert a.block.dedicated and a.offset == 0 and a.block.size == size
        else:
            assert not a.block.dedicated and a.block.size == block
        live.append(a)
        if free_one and len(live) > 1:
            sub.free(live.pop(0))
        assert_disjoint(live, block)
    s = sub.stats
    assert s.bound_bytes == sum(a.size for a in live)
    assert s.allocations == s.blocks + s.dedicated == len(backend.made) - len(backend.freed)
    assert s.allocated_bytes >= s.bound_bytes
    sub.release_all()
    assert sorted(backend.freed) == list(range(len(backend.made)))
    assert sub.stats.allocations == 0 and sub.stats.allocated_bytes == 0


def test_more_than_half_a_block_is_dedicated():
    sub = SubAllocator(4 * MIB, CountingBackend())
    half = sub.allocate(2 * MIB, 16, 0)
    over = sub.allocate(2 * MIB + 1, 16, 0)
    assert not half.block.dedicated and half.block.size == 4 * MIB
    assert over.block.dedicated and over.block.size == 2 * MIB + 1
    assert (sub.stats.blocks, sub.stats.dedicated, sub.stats.allocations) == (1, 1, 2)


def test_block_size_zero_is_one_allocation_per_buffer():
    backend = CountingBackend()
    sub = SubAllocator(0, backend)
    allocs = [sub.allocate(3200, 16, 0) for _ in range(50)]
    assert len({id(a.block) for a in allocs}) == 50
    assert sub.stats.allocations == sub.stats.dedicated == 50
    assert sub.stats.allocated_bytes == sub.stats.bound_bytes == 50 * 3200
    sub.free(allocs[7])  # dedicated memory goes back at once
    assert backend.freed == [allocs[7].block.handle] and sub.stats.allocations == 49


def test_full_block_opens_a_new_one_and_freed_space_is_reused():
    backend = CountingBackend()
    sub = SubAllocator(1 * MIB, backend)
    size = 64 * 1024
    first = [sub.allocate(size, 256, 0) for _ in range(16)]  # exactly fills the block
    assert sub.stats.blocks == 1
    extra = sub.allocate(size, 256, 0)
    assert sub.stats.blocks == 2 and extra.block is not first[0].block
    sub.free(first[5])
    again = sub.allocate(size, 256, 0)  # first fit: back into the first block's hole
    assert again.block is first[0].block and again.offset == first[5].offset
    assert sub.stats.blocks == 2 and len(backend.made) == 2


def test_memory_types_never_share_a_block():
    sub = SubAllocator(4 * MIB, CountingBackend())
    a = sub.allocate(1000, 16, 1)
    b = sub.allocate(1000, 16, 3)
    assert a.block is not b.block and (a.block.type_index, b.block.type_index) == (1, 3)


def test_trim_releases_only_empty_blocks():
    backend = CountingBackend()
    sub = SubAllocator(1 * MIB, backend)
    keep = sub.allocate(1000, 16, 0)
    gone = sub.allocate(1000, 16, 2)
    sub.free(gone)
    assert sub.stats.blocks == 2  # shared blocks stay until trimmed
    assert sub.trim() == 1
    assert backend.freed == [gone.block.handle] and keep.block.live == 1


def test_allocation_limit_is_reported_not_exceeded():
    backend = CountingBackend()
    sub = SubAllocator(0, backend, max_allocations=3)
    for _ in range(3):
        sub.allocate(100, 16, 0)
    with pytest.raises(AllocationLimitError, match=r"4 live device-memory allocations needed, but the limit is 3") as err:
        sub.allocate(100, 16, 0)
    assert (err.value.needed, err.value.limit) == (4, 3)
    assert len(backend.made) == 3  # the backend was never asked for the fourth
    with pytest.raises(AllocationLimitError, match="5000 live"):
        sub.check_room(4997)
    # blocks fit many buffers under the same limit
    blocks = SubAllocator(4 * MIB, CountingBackend(), max_allocations=3)
    for _ in range(1000):
        blocks.allocate(3200, 16, 0)
    assert blocks.stats.allocations == 1


def test_limit_not_enforced_lets_the_backend_decide():
    backend = CountingBackend()
    sub = SubAllocator(0, backend, max_allocations=2, enforce_limit=False)
    for _ in range(5):
        sub.allocate(100, 16, 0)
    assert len(backend.made) == 5


def test_choose_memory_type():
    device_local, host_visible, coherent = 1, 2, 4
    flags = [device_local, host_visible | coherent, device_local | host_visible | coherent]
    assert choose_memory_type(0b111, flags, device_local) == 0
    assert choose_memory_type(0b111, flags, host_visible | coherent) == 1
    assert choose_memory_type(0b100, flags, host_visible | coherent) == 2  # memoryTypeBits rule out type 1
    assert choose_memory_type(0b111, flags, host_visible, avoid=device_local) == 1
    with pytest.raises(Exception, match="no memory type"):
        choose_memory_type(0b001, flags, host_visible)
