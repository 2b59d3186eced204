"""A device-memory suballocator for mesh vertex buffers (the allocator experiment, issue 4.7).

Two layers:

- ``SubAllocator`` (pure logic, no Vulkan): places ``(size, alignment, memory type)`` requests
  into fixed-size blocks, one list of blocks per memory type, first fit over the blocks in
  creation order and TLSF (``rgraph.memory.tlsf``) inside each block; a request larger than
  half a block gets a dedicated allocation, as general-purpose allocators (VMA) do;
  ``block_size=0`` means one allocation per request. It asks a *backend* for the memory
  itself and refuses, with ``AllocationLimitError``, to go past ``max_allocations`` (the
  device's ``maxMemoryAllocationCount``: 4096 on NVIDIA, 2^32-1 on lavapipe).
- ``MeshPool`` (Vulkan): one VkBuffer per mesh (or per mesh and frame-in-flight copy), its
  real ``vkGetBufferMemoryRequirements`` size, alignment and memoryTypeBits, bound at the
  suballocated offset. Static buffers are device-local and filled through a host staging
  buffer (``vkCmdCopyBuffer`` then one global memory barrier COPY/TRANSFER_WRITE ->
  VERTEX_ATTRIBUTE_INPUT/VERTEX_ATTRIBUTE_READ in the same command buffer: a fence wait alone
  does not make device writes visible). Dynamic buffers live in host-visible coherent memory,
  persistently mapped per memory object, and are written by the CPU through NumPy views.

Statistics (``MeshPool.stats``): live and peak allocation counts, bytes allocated
(VkDeviceMemory sizes), bytes bound (buffer requirement sizes), bytes used (data), and the wall
time spent in each kind of Vulkan call.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from rgraph.memory.model import align_up
from rgraph.memory.tlsf import Tlsf
from rgraph.vk.errors import ExecutionError

MIB = 1 << 20
STAGING_CHUNK = 64 * MIB
#: Dynamic buffers are written as rows of 16 bytes (vec4 vertices): keep them 16-aligned.
ROW_BYTES = 16


class AllocationLimitError(ExecutionError):
    """More live VkDeviceMemory objects than the device's maxMemoryAllocationCount (or a lower
    limit given for a rehearsal)."""

    def __init__(self, needed: int, limit: int, what: str = "", limit_name: str = "the device's maxMemoryAllocationCount") -> None:
        self.needed = needed
        self.limit = limit
        super().__init__(f"{what}{needed} live device-memory allocations needed, but the limit is {limit} "
                         f"({limit_name}); use a block size > 0 (suballocation)")


class MemoryBackend(Protocol):
    def allocate(self, type_index: int, size: int) -> Any: ...

    def free(self, block: MemoryBlock) -> None: ...


@dataclass(eq=False)
class MemoryBlock:
    """One VkDeviceMemory (or a fake backend's handle): a shared block or a dedicated allocation."""

    handle: Any
    size: int
    type_index: int
    tlsf: Tlsf | None  # None: dedicated to one request
    live: int = 0
    mapped: Any = None  # the backend's mapping, when it made one
    rows: np.ndarray | None = None  # float32 (size // 16, 4) view of ``mapped``

    @property
    def dedicated(self) -> bool:
        return self.tlsf is None


@dataclass(frozen=True, eq=False)
class Allocation:
    block: MemoryBlock
    offset: int
    size: int


@dataclass
class AllocatorStats:
    allocations: int = 0  # live memory objects
    peak_allocations: int = 0
    blocks: int = 0  # live shared blocks
    dedicated: int = 0  # live dedicated allocations
    allocated_bytes: int = 0  # sum of live memory object sizes
    bound_bytes: int = 0  # sum of live request sizes
    vk_allocate_s: float = 0.0  # wall time inside backend.allocate
    vk_free_s: float = 0.0


class SubAllocator:
    """Fixed-size blocks per memory type with TLSF inside; dedicated for large requests."""

    def __init__(self, block_size: int, backend: MemoryBackend, max_allocations: int | None = None,
                 enforce_limit: bool = True) -> None:
        if block_size < 0:
            raise ValueError("block_size must be >= 0")
        self.block_size = block_size
        self.backend = backend
        self.max_allocations = max_allocations
        self.enforce_limit = enforce_limit
        self.limit_name = "the device's maxMemoryAllocationCount"  # how the limit is named in errors
        self.blocks: dict[int, list[MemoryBlock]] = {}  # shared blocks per memory type, in creation order
        self.dedicated_blocks: dict[int, MemoryBlock] = {}  # id -> block (O(1) release)
        self.stats = AllocatorStats()

    def is_dedicated_size(self, size: int) -> bool:
        return self.block_size == 0 or size > self.block_size // 2

    def allocate(self, size: int, alignment: int, type_index: int) -> Allocation:
        size = max(int(size), 1)
        alignment = max(int(alignment), 1)
        if self.is_dedicated_size(size):
            block = self._new_memory(type_index, size, shared=False)
            offset = 0
        else:
            offset = None
            for block in self.blocks.get(type_index, ()):
                assert block.tlsf is not None
                offset = _fit(block.tlsf, size, alignment)
                if offset is not None:
                    break
            else:
                block = self._new_memory(type_index, self.block_size, shared=True)
                assert block.tlsf is not None
                offset = block.tlsf.allocate(size, alignment)
                if offset is None:  # padding cannot fit: give the request its own memory
                    self._release(block)
                    block = self._new_memory(type_index, size, shared=False)
                    offset = 0
        block.live += 1
        self.stats.bound_bytes += size
        return Allocation(block, offset, size)

    def free(self, allocation: Allocation) -> None:
        """Release one request; dedicated memory goes back at once, shared blocks stay (see ``trim``)."""
        block = allocation.block
        block.live -= 1
        self.stats.bound_bytes -= allocation.size
        if block.tlsf is None:
            self._release(block)
        else:
            block.tlsf.free(allocation.offset)

    def trim(self) -> int:
        """Release the shared blocks holding nothing; returns how many."""
        empty = [b for blocks in self.blocks.values() for b in blocks if b.live == 0]
        for b in empty:
            self._release(b)
        return len(empty)

    def release_all(self) -> None:
        for blocks in list(self.blocks.values()):
            for b in list(blocks):
                self._release(b)
        for b in list(self.dedicated_blocks.values()):
            self._release(b)

    def check_room(self, extra: int, what: str = "") -> None:
        """Raise ``AllocationLimitError`` if ``extra`` more memory objects would pass the limit."""
        if self.enforce_limit and self.max_allocations is not None \
                and self.stats.allocations + extra > self.max_allocations:
            raise AllocationLimitError(self.stats.allocations + extra, self.max_allocations, what, self.limit_name)

    # ---------------------------------------------------------------- internals
    def _new_memory(self, type_index: int, size: int, shared: bool) -> MemoryBlock:
        self.check_room(1)
        t0 = time.perf_counter()
        handle = self.backend.allocate(type_index, size)
        self.stats.vk_allocate_s += time.perf_counter() - t0
        block = MemoryBlock(handle, size, type_index, Tlsf(size) if shared else None)
        if shared:
            self.blocks.setdefault(type_index, []).append(block)
            self.stats.blocks += 1
        else:
            self.dedicated_blocks[id(block)] = block
            self.stats.dedicated += 1
        s = self.stats
        s.allocations += 1
        s.peak_allocations = max(s.peak_allocations, s.allocations)
        s.allocated_bytes += size
        return block

    def _release(self, block: MemoryBlock) -> None:
        if block.dedicated:
            del self.dedicated_blocks[id(block)]
            self.stats.dedicated -= 1
        else:
            self.blocks[block.type_index].remove(block)
            self.stats.blocks -= 1
        t0 = time.perf_counter()
        self.backend.free(block)
        self.stats.vk_free_s += time.perf_counter() - t0
        self.stats.allocations -= 1
        self.stats.allocated_bytes -= block.size


def _fit(tlsf: Tlsf, size: int, alignment: int) -> int | None:
    """TLSF good fit, then first fit over the free ranges: TLSF searches for size + alignment - 1
    bytes, so it misses a free range that is already aligned and exactly large enough (the last
    hole of a nearly full block)."""
    offset = tlsf.allocate(size, alignment)
    if offset is not None or alignment == 1:
        return offset
    for start, length in tlsf.free_by_start.items():
        if align_up(start, alignment) + size <= start + length:
            return tlsf._carve(start, size, alignment)  # noqa: SLF001 -- the same module family's allocator
    return None


def choose_memory_type(type_bits: int, type_flags: Sequence[int], required: int, avoid: int = 0) -> int:
    """The first memory type allowed by ``type_bits`` having every ``required`` flag,
    preferring types without ``avoid`` flags (Vulkan lists the best types first)."""
    candidates = [i for i, flags in enumerate(type_flags) if type_bits >> i & 1 and flags & required == required]
    if not candidates:
        raise ExecutionError(f"no memory type with flags {required:#x} among memoryTypeBits {type_bits:#x}")
    preferred = [i for i in candidates if not type_flags[i] & avoid]
    return (preferred or candidates)[0]


# ==================================================================== Vulkan
@dataclass(eq=False)
class PoolBuffer:
    """One VkBuffer bound into the pool: ``used`` data bytes of a ``capacity``-byte buffer."""

    handle: Any
    allocation: Allocation
    capacity: int  # bytes the buffer was created with (>= used: room to grow)
    used: int
    dynamic: bool

    @property
    def first_row(self) -> int:
        """Index of the buffer's first 16-byte row in its memory block's mapping."""
        return self.allocation.offset // ROW_BYTES


class _VulkanBackend:
    def __init__(self, device: Any) -> None:
        from rgraph.vk.loader import vk

        self.v = vk()
        self.device = device
        self.host_visible = self.v.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT
        self.type_flags = [device.memory_properties.memoryTypes[i].propertyFlags
                           for i in range(device.memory_properties.memoryTypeCount)]

    def allocate(self, type_index: int, size: int) -> Any:
        v = self.v
        try:
            return v.vkAllocateMemory(self.device.handle, v.VkMemoryAllocateInfo(
                allocationSize=size, memoryTypeIndex=type_index), None)
        except v.VkError as exc:
            raise ExecutionError(f"vkAllocateMemory of {size} bytes (memory type {type_index}) failed: "
                                 f"{type(exc).__name__}") from None

    def free(self, block: MemoryBlock) -> None:
        if block.mapped is not None:
            self.v.vkUnmapMemory(self.device.handle, block.handle)
            block.mapped = block.rows = None
        self.v.vkFreeMemory(self.device.handle, block.handle, None)

    def map(self, block: MemoryBlock) -> np.ndarray:
        """A float32 (rows, 4) view of the whole memory object (mapped once, kept mapped)."""
        if block.rows is None:
            block.mapped = self.v.vkMapMemory(self.device.handle, block.handle, 0, block.size, 0)
            rows = block.size // ROW_BYTES
            block.rows = np.frombuffer(block.mapped, dtype=np.float32, count=rows * 4).reshape(rows, 4)
        return block.rows


@dataclass
class PoolTimes:
    create_s: float = 0.0  # vkCreateBuffer + vkGetBufferMemoryRequirements + vkBindBufferMemory
    upload_s: float = 0.0  # staging fill, copy recording, submit and fence wait
    map_s: float = 0.0  # mapping and the first CPU fill of dynamic buffers
    destroy_s: float = 0.0
    timeline: list[tuple[str, float]] = field(default_factory=list)


class MeshPool:
    """Vertex buffers suballocated from fixed-size VkDeviceMemory blocks (see the module docstring).

    ``block_size`` 0: one allocation per buffer. ``max_allocations`` lowers the device's
    ``maxMemoryAllocationCount`` (to rehearse the NVIDIA limit on lavapipe); ``enforce_limit``
    False lets the driver decide past the limit (invalid usage: the validation layer reports it).
    ``dynamic_device_local`` puts dynamic buffers in DEVICE_LOCAL | HOST_VISIBLE | HOST_COHERENT
    memory (resizable BAR) when a type has those flags, else in the first host-visible one.
    """

    def __init__(self, device: Any, block_size: int, *, max_allocations: int | None = None,
                 enforce_limit: bool = True, dynamic_device_local: bool = False) -> None:
        from rgraph.vk.loader import vk

        v = vk()
        self.v = v
        self.device = device
        self.device_limit = int(device.properties.limits.maxMemoryAllocationCount)
        limit = self.device_limit if max_allocations is None else min(self.device_limit, int(max_allocations))
        self.backend = _VulkanBackend(device)
        self.allocator = SubAllocator(block_size, self.backend, limit, enforce_limit)
        if limit < self.device_limit:
            self.allocator.limit_name = (f"lowered for a rehearsal; the device's maxMemoryAllocationCount "
                                         f"is {self.device_limit}")
        self.buffers: list[PoolBuffer] = []
        self.times = PoolTimes()
        self.used_bytes = 0
        self._usage = v.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT
        self._static_usage = self._usage | v.VK_BUFFER_USAGE_TRANSFER_DST_BIT
        self._device_local = v.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT
        self._host = v.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | v.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
        # dynamic buffers: plain host memory (the first host-visible coherent type), or, when
        # asked, device-local host-visible memory (resizable BAR) where the device has it
        self._dynamic_prefer = self._device_local if dynamic_device_local else 0

    @property
    def limit(self) -> int | None:
        return self.allocator.max_allocations

    # ---------------------------------------------------------------- buffers
    def create_buffer(self, used: int, capacity: int | None = None, *, dynamic: bool = False) -> PoolBuffer:
        """A vertex buffer of ``capacity`` bytes (default ``used``): device-local and a copy
        destination when static, host-visible coherent and mapped when ``dynamic``."""
        v = self.v
        dev = self.device.handle
        capacity = max(int(capacity if capacity is not None else used), ROW_BYTES)
        t0 = time.perf_counter()
        handle = v.vkCreateBuffer(dev, v.VkBufferCreateInfo(
            size=capacity, usage=self._usage if dynamic else self._static_usage,
            sharingMode=v.VK_SHARING_MODE_EXCLUSIVE), None)
        req = v.vkGetBufferMemoryRequirements(dev, handle)
        flags = self.backend.type_flags
        try:
            if dynamic:
                type_index = self._dynamic_type(req.memoryTypeBits)
                alignment = max(int(req.alignment), ROW_BYTES)  # rows of the NumPy mapping view
            else:
                type_index = choose_memory_type(req.memoryTypeBits, flags, self._device_local)
                alignment = int(req.alignment)
            t1 = time.perf_counter()
            allocation = self.allocator.allocate(int(req.size), alignment, type_index)
            t2 = time.perf_counter()
        except BaseException:
            v.vkDestroyBuffer(dev, handle, None)
            raise
        v.vkBindBufferMemory(dev, handle, allocation.block.handle, allocation.offset)
        self.times.create_s += (t1 - t0) + (time.perf_counter() - t2)
        buf = PoolBuffer(handle, allocation, capacity, int(used), dynamic)
        self.buffers.append(buf)
        self.used_bytes += buf.used
        return buf

    def _dynamic_type(self, type_bits: int) -> int:
        flags = self.backend.type_flags
        if self._dynamic_prefer:
            try:
                return choose_memory_type(type_bits, flags, self._host | self._dynamic_prefer)
            except ExecutionError:
                pass  # no resizable BAR: plain host memory
        return choose_memory_type(type_bits, flags, self._host)

    def rows(self, buf: PoolBuffer) -> np.ndarray:
        """The float32 (rows, 4) mapping of ``buf``'s memory block (dynamic buffers only)."""
        if not buf.dynamic:
            raise ExecutionError("static mesh buffers are device-local: write them with upload()")
        t0 = time.perf_counter()
        rows = self.backend.map(buf.allocation.block)
        self.times.map_s += time.perf_counter() - t0
        return rows

    def write(self, buf: PoolBuffer, vertices: np.ndarray) -> None:
        """Write float32 vec4 ``vertices`` at the start of a dynamic buffer."""
        data = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 4)
        if data.nbytes > buf.capacity:
            raise ExecutionError(f"{data.nbytes} bytes do not fit a buffer of capacity {buf.capacity}")
        rows = self.rows(buf)
        t0 = time.perf_counter()
        rows[buf.first_row:buf.first_row + len(data)] = data
        self.times.map_s += time.perf_counter() - t0

    def upload(self, items: Sequence[tuple[PoolBuffer, np.ndarray]], queue: Any, family: int) -> None:
        """Fill static buffers from host data through a staging buffer, in chunks of at most
        ``STAGING_CHUNK`` bytes: copies, then one memory barrier to vertex-attribute reads."""
        from rgraph.vk.resources import HostBuffer

        v = self.v
        dev = self.device.handle
        if not items:
            return
        t0 = time.perf_counter()
        total = sum(int(np.asarray(a).nbytes) for _, a in items)
        chunk = min(STAGING_CHUNK, max(total, ROW_BYTES))
        if any(np.asarray(a).nbytes > chunk for _, a in items):
            chunk = max(int(np.asarray(a).nbytes) for _, a in items)
        self.allocator.check_room(1, "staging for the upload: ")
        staging = HostBuffer.create(self.device, chunk, v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
        pool = v.vkCreateCommandPool(dev, v.VkCommandPoolCreateInfo(
            flags=v.VK_COMMAND_POOL_CREATE_TRANSIENT_BIT, queueFamilyIndex=family), None)
        fence = v.vkCreateFence(dev, v.VkFenceCreateInfo(), None)
        try:
            staged = np.frombuffer(staging.mapped, dtype=np.uint8, count=chunk)
            start = 0
            while start < len(items):
                offset, end = 0, start
                while end < len(items) and offset + np.asarray(items[end][1]).nbytes <= chunk:
                    data = np.ascontiguousarray(items[end][1]).view(np.uint8).reshape(-1)
                    staged[offset:offset + data.nbytes] = data
                    offset += data.nbytes
                    end += 1
                self._submit_copies(pool, fence, queue, staging.handle, items[start:end])
                start = end
        finally:
            v.vkDestroyFence(dev, fence, None)
            v.vkDestroyCommandPool(dev, pool, None)
            staging.destroy()
        self.times.upload_s += time.perf_counter() - t0

    def _submit_copies(self, pool: Any, fence: Any, queue: Any, staging: Any,
                       items: Sequence[tuple[PoolBuffer, np.ndarray]]) -> None:
        v = self.v
        dev = self.device.handle
        cb = v.vkAllocateCommandBuffers(dev, v.VkCommandBufferAllocateInfo(
            commandPool=pool, level=v.VK_COMMAND_BUFFER_LEVEL_PRIMARY, commandBufferCount=1))[0]
        v.vkBeginCommandBuffer(cb, v.VkCommandBufferBeginInfo(flags=v.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))
        src = 0
        for buf, data in items:
            n = int(np.asarray(data).nbytes)
            v.vkCmdCopyBuffer(cb, staging, buf.handle, 1, [v.VkBufferCopy(srcOffset=src, dstOffset=0, size=n)])
            src += n
        # One global barrier instead of one VkBufferMemoryBarrier2 per buffer (10,000 of them
        # would cost ~0.1 s of struct building in Python): the same COPY -> vertex-input
        # dependency for every buffer written above.
        barrier = v.VkMemoryBarrier2(
            srcStageMask=v.VK_PIPELINE_STAGE_2_COPY_BIT, srcAccessMask=v.VK_ACCESS_2_TRANSFER_WRITE_BIT,
            dstStageMask=v.VK_PIPELINE_STAGE_2_VERTEX_ATTRIBUTE_INPUT_BIT,
            dstAccessMask=v.VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT)
        v.vkCmdPipelineBarrier2(cb, v.VkDependencyInfo(memoryBarrierCount=1, pMemoryBarriers=[barrier]))
        v.vkEndCommandBuffer(cb)
        self._submit_wait(cb, pool, fence, queue)

    def _submit_wait(self, cb: Any, pool: Any, fence: Any, queue: Any) -> None:
        v = self.v
        dev = self.device.handle
        v.vkQueueSubmit2(queue, 1, [v.VkSubmitInfo2(commandBufferInfoCount=1, pCommandBufferInfos=[
            v.VkCommandBufferSubmitInfo(commandBuffer=cb)])], fence)
        v.vkWaitForFences(dev, 1, [fence], v.VK_TRUE, self.device.fence_timeout_ns)
        v.vkResetFences(dev, 1, [fence])
        v.vkFreeCommandBuffers(dev, pool, 1, [cb])

    # ---------------------------------------------------------------- teardown
    def destroy(self) -> None:
        """Destroy every buffer and free every memory object (idempotent)."""
        v = self.v
        t0 = time.perf_counter()
        for buf in reversed(self.buffers):
            v.vkDestroyBuffer(self.device.handle, buf.handle, None)
            self.allocator.free(buf.allocation)
        self.buffers = []
        self.used_bytes = 0
        self.allocator.release_all()
        self.times.destroy_s += time.perf_counter() - t0

    # ---------------------------------------------------------------- statistics
    def stats(self) -> dict[str, Any]:
        s = self.allocator.stats
        return {
            "block_bytes": self.allocator.block_size,
            "allocations": s.allocations, "peak_allocations": s.peak_allocations,
            "blocks": s.blocks, "dedicated": s.dedicated,
            "allocated_bytes": s.allocated_bytes, "bound_bytes": s.bound_bytes, "used_bytes": self.used_bytes,
            "internal_fragmentation": (1 - s.bound_bytes / s.allocated_bytes) if s.allocated_bytes else 0.0,
            "buffers": len(self.buffers),
            "max_memory_allocation_count": self.device_limit, "limit": self.limit,
            "vk_allocate_ms": s.vk_allocate_s * 1e3, "create_bind_ms": self.times.create_s * 1e3,
            "upload_ms": self.times.upload_s * 1e3, "map_fill_ms": self.times.map_s * 1e3,
            "destroy_ms": self.times.destroy_s * 1e3, "vk_free_ms": s.vk_free_s * 1e3,
        }


def align_rows(nbytes: int) -> int:
    """``nbytes`` rounded up to whole 16-byte rows."""
    return align_up(int(nbytes), ROW_BYTES)
