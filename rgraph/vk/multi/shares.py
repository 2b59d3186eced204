"""Sort-last draw partitions: the scene's draw calls split over devices by triangle count."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


def triangles(call: Any) -> int:
    return (call.index_count // 3) * max(1, call.instances)


def share_of(calls: Sequence[Any], device: int, devices: int) -> list[Any]:
    """Device ``device``'s calls, in their original order: largest first to the least-loaded
    device (ties: lowest device), so every device's triangle count is within one call's of the others'."""
    load = [0] * devices
    owner: dict[int, int] = {}
    for i in sorted(range(len(calls)), key=lambda i: (-triangles(calls[i]), i)):
        d = min(range(devices), key=lambda k: (load[k], k))
        owner[i] = d
        load[d] += triangles(calls[i])
    return [c for i, c in enumerate(calls) if owner[i] == device]
