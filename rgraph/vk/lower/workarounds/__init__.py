"""Workarounds for Khronos validation layer 1.3.239, in the order the lowering applies them.

Each is a rewrite that records the same dependency (or a wider one) in the form that layer
checks; none is needed by the Vulkan spec. ``rgraph run --no-layer-workarounds`` (and
``lower(..., workarounds=())``) switches them all off; a subset can be named.

- ``transfer_stages``: plan-wide, narrow transfer stages (COPY, ...) -> ALL_TRANSFER.
- ``name_read_write``: a barrier after reads of a write also names that write
  (``after_reads``).
- ``memory_read_after_reads``: a layout transition after reads names MEMORY_READ
  (``after_reads``).
- ``packed_range_global_barrier``: an aliasing hand-off the layer sees in part also records
  a global memory barrier (``packed_ranges``).
- ``layer_race_edges``: semaphore edges where the layer's cross-queue racing check would
  report a false positive (``layer_races``).
"""

from __future__ import annotations

LAYER_WORKAROUNDS: tuple[str, ...] = (
    "transfer_stages",
    "name_read_write",
    "memory_read_after_reads",
    "packed_range_global_barrier",
    "layer_race_edges",
)


def check_names(names: tuple[str, ...] | list[str]) -> tuple[str, ...]:
    unknown = [n for n in names if n not in LAYER_WORKAROUNDS]
    if unknown:
        raise ValueError(f"unknown layer workaround(s) {', '.join(unknown)}; known: {', '.join(LAYER_WORKAROUNDS)}")
    return tuple(n for n in LAYER_WORKAROUNDS if n in names)
