"""Scene buffers against the device's descriptor range limits, before they are bound.

A storage buffer binding may span at most ``maxStorageBufferRange`` bytes (128 MiB on
lavapipe: 699,050 instances of 192 bytes), a uniform one ``maxUniformBufferRange``. A scene
whose table is larger cannot be bound whole: refuse it with its size and the limit rather than
write an invalid descriptor (a validation error, undefined reads past the limit without one).
"""

from __future__ import annotations

from collections.abc import Iterable

from rgraph.vk.errors import ExecutionError


def check_ranges(bindings: Iterable[tuple[str, bool, int]], max_storage: int, max_uniform: int,
                 draws: int) -> None:
    """``bindings``: (what, is uniform, bytes) of each scene binding; raise on the first over its limit."""
    for what, uniform, size in bindings:
        limit, name = (max_uniform, "maxUniformBufferRange") if uniform else (max_storage, "maxStorageBufferRange")
        if size > limit:
            raise ExecutionError(
                f"the scene's {what} is {size:,} bytes ({draws:,} draws), over this device's {name} of "
                f"{limit:,} bytes: use fewer instances or lights (about {draws * limit // size:,} draws fit)")
