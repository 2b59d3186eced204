"""What the checker reports: the ``Hazard`` record and the kinds it can have."""

from __future__ import annotations

from dataclasses import dataclass

RAW = "RAW"
WAR = "WAR"
WAW = "WAW"
LAYOUT_MISMATCH = "layout mismatch"
UNDEFINED_CONTENTS = "undefined contents"
QUEUE_OWNERSHIP = "queue ownership"
SEMAPHORE = "semaphore"
ALIASING_OVERLAP = "aliasing overlap"
ALIASING_HANDOFF = "aliasing hand-off"
FINAL_STATE = "final state"
LIFETIME = "lifetime"
MEMORY_LAYOUT = "memory layout"

ALL_KINDS = frozenset({
    RAW, WAR, WAW, LAYOUT_MISMATCH, UNDEFINED_CONTENTS, QUEUE_OWNERSHIP, SEMAPHORE,
    ALIASING_OVERLAP, ALIASING_HANDOFF, FINAL_STATE, LIFETIME, MEMORY_LAYOUT,
})

Subresource = tuple[tuple[int, int], tuple[int, int]]  # (mips [begin, end), layers [begin, end))


@dataclass(frozen=True, slots=True)
class Hazard:
    """One hazard. ``message`` is the whole report line; the other fields locate it.

    ``pass_index``/``pass_name`` are None for frame-level findings (end-of-frame state,
    aliasing between resources); ``subresource`` is None for buffers and whole-resource
    findings.
    """

    kind: str
    pass_index: int | None
    pass_name: str | None
    resource: str | None
    subresource: Subresource | None
    message: str

    def __str__(self) -> str:
        return self.message


def format_subresource(sub: Subresource | None) -> str:
    if sub is None:
        return ""
    (m0, m1), (l0, l1) = sub
    return f"[mips {m0}:{m1}, layers {l0}:{l1}]"
