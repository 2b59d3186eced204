"""A two-level segregated fit (TLSF) sub-allocator over one address range.

Free ranges live in bins indexed by (first level = floor(log2 size), second level = the next
``SL_BITS`` bits of the size); two bitmap levels find the first non-empty bin that is certain
to hold a request in O(1) ("good fit"). Freed ranges merge with free neighbours. A growable
allocator extends its range at the top when nothing fits; its ``size`` is the high-water mark.
"""

from __future__ import annotations

from rgraph.memory.model import align_up

SL_BITS = 4
SL_COUNT = 1 << SL_BITS


def _bin(size: int) -> tuple[int, int]:
    """Bin holding free ranges of ``size`` bytes (size >= 1)."""
    if size < SL_COUNT:
        return 0, size
    fl = size.bit_length() - 1
    return fl - SL_BITS + 1, (size >> (fl - SL_BITS)) - SL_COUNT


def _bin_for_request(size: int) -> tuple[int, int]:
    """First bin all of whose ranges are >= ``size`` (rounds the request up)."""
    if size >= SL_COUNT:
        size += (1 << (size.bit_length() - 1 - SL_BITS)) - 1
    return _bin(size)


class Tlsf:
    def __init__(self, size: int = 0, growable: bool = False):
        self.size = size
        self.growable = growable
        self.fl_bitmap = 0
        self.sl_bitmaps: dict[int, int] = {}
        self.bins: dict[tuple[int, int], list[int]] = {}
        self.free_by_start: dict[int, int] = {}  # offset -> length
        self.free_by_end: dict[int, int] = {}  # end -> offset
        self.used: dict[int, int] = {}  # offset of an allocation -> length of its range
        if size > 0:
            self._insert_free(0, size)

    # -- free-range bookkeeping -------------------------------------------------------
    def _insert_free(self, offset: int, length: int) -> None:
        fl, sl = _bin(length)
        self.bins.setdefault((fl, sl), []).append(offset)
        self.sl_bitmaps[fl] = self.sl_bitmaps.get(fl, 0) | (1 << sl)
        self.fl_bitmap |= 1 << fl
        self.free_by_start[offset] = length
        self.free_by_end[offset + length] = offset

    def _remove_free(self, offset: int) -> int:
        length = self.free_by_start.pop(offset)
        del self.free_by_end[offset + length]
        fl, sl = _bin(length)
        entries = self.bins[(fl, sl)]
        entries.remove(offset)
        if not entries:
            del self.bins[(fl, sl)]
            self.sl_bitmaps[fl] &= ~(1 << sl)
            if not self.sl_bitmaps[fl]:
                self.fl_bitmap &= ~(1 << fl)
        return length

    def _find_bin(self, fl: int, sl: int) -> tuple[int, int] | None:
        sl_map = self.sl_bitmaps.get(fl, 0) & (~0 << sl)
        if not sl_map:
            fl_map = self.fl_bitmap & (~0 << (fl + 1))
            if not fl_map:
                return None
            fl = (fl_map & -fl_map).bit_length() - 1
            sl_map = self.sl_bitmaps[fl]
        return fl, (sl_map & -sl_map).bit_length() - 1

    # -- allocation -----------------------------------------------------------------------
    def allocate(self, size: int, alignment: int) -> int | None:
        """Offset of ``size`` bytes aligned to ``alignment``, or None when a fixed-size
        allocator has no room."""
        size = max(size, 1)
        request = size + alignment - 1 if alignment > 1 else size
        found = self._find_bin(*_bin_for_request(request))
        candidate = self.bins[found][-1] if found else self._exact_bin_fit(request)
        if candidate is None:
            if not self.growable:
                return None
            candidate = self._grow_for(size, alignment)
        return self._carve(candidate, size, alignment)

    def _exact_bin_fit(self, request: int) -> int | None:
        for offset in self.bins.get(_bin(request), ()):
            if self.free_by_start[offset] >= request:
                return offset
        return None

    def _grow_for(self, size: int, alignment: int) -> int:
        """Extend the range at its top so that a free range there can hold the request."""
        start = self.free_by_end.get(self.size, self.size)
        # a top free range that already fits (missed by the bin search's rounding) must not shrink the heap
        needed_end = max(align_up(start, alignment) + size, self.size)
        if start in self.free_by_start:
            self._remove_free(start)
        self._insert_free(start, needed_end - start)
        self.size = needed_end
        return start

    def _carve(self, offset: int, size: int, alignment: int) -> int:
        length = self._remove_free(offset)
        aligned = align_up(offset, alignment)
        if aligned > offset:
            self._insert_free(offset, aligned - offset)
        tail = offset + length - (aligned + size)
        if tail > 0:
            self._insert_free(aligned + size, tail)
        self.used[aligned] = size
        return aligned

    def free(self, offset: int) -> None:
        """Release the allocation at ``offset``, merging with free neighbours."""
        start = offset
        end = offset + self.used.pop(offset)
        prev = self.free_by_end.get(start)
        if prev is not None:
            self._remove_free(prev)
            start = prev
        if end in self.free_by_start:
            end += self._remove_free(end)
        self._insert_free(start, end - start)

    @property
    def empty(self) -> bool:
        return not self.used
