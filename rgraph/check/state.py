"""What the replay remembers about each subresource cell: immutable records and states."""

from __future__ import annotations

from dataclasses import dataclass

READ = 0
WRITE = 1
TRANSITION = 2


@dataclass(frozen=True, slots=True)
class Rec:
    """One past access of a cell at one pipeline stage (or a layout transition).

    ``cls`` is the execution-chain class (chains.py) on ``queue``: for reads, the chain
    of the read itself; for writes and transitions, the chain that starts where the write
    was made available (-1: not made available yet). ``vis`` lists (stages, accesses)
    rectangles the write has been made visible to. ``xvis`` lists (queue, stages, accesses)
    for other queues: what a barrier there, chained after a semaphore wait, made visible.
    """

    kind: int
    queue: int
    pass_index: int  # -1: the previous frame's final access
    stage: int  # one concrete stage bit; 0 for a transition
    access: int
    cls: int
    origin: str  # e.g. "pass 3 'sss_h'" or "barrier 0 of pass 3 'sss_h'"
    vis: tuple[tuple[int, int], ...] = ()
    xvis: tuple[tuple[int, int, int], ...] = ()


@dataclass(frozen=True, slots=True)
class Release:
    """A queue-family release waiting for its acquire."""

    src_queue: int
    dst_queue: int
    src_layout: str | None
    dst_layout: str | None
    pass_index: int
    origin: str


@dataclass(frozen=True, slots=True)
class CellState:
    layout: str | None  # None for buffers
    owner: int  # queue index; -1: no queue has used it yet
    defined: bool  # contents hold data someone wrote (not discarded, not fresh)
    touched: bool  # used this frame, or carried in from the previous frame
    writes: tuple[Rec, ...] = ()  # the last write (one record per stage)
    reads: tuple[Rec, ...] = ()  # reads since the last write
    release: Release | None = None
    discarded_by: str | None = None  # origin of the UNDEFINED transition that dropped contents
