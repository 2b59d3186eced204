"""Per-resource state over subresource ranges, not per cell.

For each mip level, the layers are split into intervals, each with one immutable state
object (an interval map searched with bisect). An update splits the intervals at the
range ends, maps each old state to a new one (once per distinct old state, so cells
that shared a state keep sharing it) and merges neighbours that end up with the same
state. A 2048-layer image used as a whole stays one interval per mip; one used layer
by layer costs a logarithmic search per access, not a walk over all layers.
"""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Callable, Iterator
from typing import Generic, TypeVar

from rgraph.check.plan import Rect

S = TypeVar("S")


def intersect(a: Rect, b: Rect) -> Rect | None:
    m0, m1 = max(a[0], b[0]), min(a[1], b[1])
    l0, l1 = max(a[2], b[2]), min(a[3], b[3])
    if m0 >= m1 or l0 >= l1:
        return None
    return (m0, m1, l0, l1)


class CellMap(Generic[S]):
    def __init__(self, whole: Rect, state: S) -> None:
        self.whole = whole
        self._end = whole[3]
        # per mip: (interval starts, their states); the last interval ends at the layer count
        self._mips: list[tuple[list[int], list[S]]] = [([whole[2]], [state]) for _ in range(whole[0], whole[1])]

    def _clip(self, rect: Rect | None) -> Rect | None:
        return self.whole if rect is None else intersect(rect, self.whole)

    def query(self, rect: Rect | None) -> Iterator[tuple[Rect, S]]:
        """(part of ``rect``, state) for each interval that ``rect`` meets, mip by mip."""
        clipped = self._clip(rect)
        if clipped is None:
            return
        m0, m1, l0, l1 = clipped
        for mip in range(m0, m1):
            starts, states = self._mips[mip]
            i = bisect_right(starts, l0) - 1
            n = len(starts)
            while i < n and starts[i] < l1:
                end = starts[i + 1] if i + 1 < n else self._end
                yield (mip, mip + 1, max(starts[i], l0), min(end, l1)), states[i]
                i += 1

    def states(self) -> Iterator[tuple[Rect, S]]:
        return self.query(None)

    def update(self, rect: Rect | None, change: Callable[[S], S]) -> None:
        """Replace the state of every cell in ``rect`` by ``change(old state)``."""
        clipped = self._clip(rect)
        if clipped is None:
            return
        m0, m1, l0, l1 = clipped
        memo: dict[int, S] = {}
        for mip in range(m0, m1):
            starts, states = self._mips[mip]
            lo = self._split(starts, states, l0)
            hi = self._split(starts, states, l1) if l1 < self._end else len(starts)
            for k in range(lo, hi):
                old = states[k]
                new = memo.get(id(old))
                if new is None:
                    new = memo[id(old)] = change(old)
                states[k] = new
            # merge equal neighbours in and around the changed run
            k = max(lo, 1)
            stop = min(hi + 1, len(starts))
            while k < stop:
                if states[k] is states[k - 1]:
                    del starts[k]
                    del states[k]
                    stop -= 1
                else:
                    k += 1

    @staticmethod
    def _split(starts: list[int], states: list[S], at: int) -> int:
        """Make ``at`` an interval start; return its index."""
        i = bisect_right(starts, at) - 1
        if starts[i] == at:
            return i
        starts.insert(i + 1, at)
        states.insert(i + 1, states[i])
        return i + 1

    def interval_count(self) -> int:
        return sum(len(starts) for starts, _ in self._mips)


def merge_rects(rects: list[Rect]) -> list[Rect]:
    """Fewer, larger rectangles covering exactly the given disjoint rectangles."""
    boxes = [list(r) for r in rects]
    while True:
        before = len(boxes)
        boxes.sort(key=lambda b: (b[0], b[1], b[2]))
        joined: list[list[int]] = []
        for box in boxes:
            last = joined[-1] if joined else None
            if last is not None and last[0] == box[0] and last[1] == box[1] and last[3] == box[2]:
                last[3] = box[3]
            else:
                joined.append(box)
        joined.sort(key=lambda b: (b[2], b[3], b[0]))
        boxes = []
        for box in joined:
            last = boxes[-1] if boxes else None
            if last is not None and last[2] == box[2] and last[3] == box[3] and last[1] == box[0]:
                last[1] = box[1]
            else:
                boxes.append(box)
        if len(boxes) == before:
            return [(b[0], b[1], b[2], b[3]) for b in boxes]
