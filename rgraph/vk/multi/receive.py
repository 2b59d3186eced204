"""Device 0 receiving a frame's tiles without re-loading its executable: the received bytes
go into its ``X.from<d>`` buffers (imported resources) through a host-visible staging buffer
and one one-time submit, fenced, between frames (the staged path of docs/multi-gpu.md)."""

from __future__ import annotations

from typing import Any

from rgraph.vk.loader import vk
from rgraph.vk.resources import staging_buffer
from rgraph.vk.runtime.one_time import _any_access, buffer_barrier, copy_write, submit_once


def refill(executable: Any, received: dict[str, bytes]) -> None:
    """Overwrite the receiving buffers of ``executable`` (an ``rgraph.api.Executable`` whose
    frames have all completed) with ``received`` (name -> bytes)."""
    v = vk()
    ex = executable.executor
    by_name = {r.plan["name"]: r for r in ex.resources.shared()}
    work = []
    for name, data in received.items():
        r = by_name.get(name)
        if r is None:
            from rgraph.vk.errors import ExecutionError

            raise ExecutionError(f"device 0's plan has no receiving buffer {name!r}")
        staging = staging_buffer(ex, "upload", name, len(data), v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
        staging.write(data)
        work.append((r, staging, len(data)))

    def record(cb: Any) -> None:
        for r, staging, size in work:
            # the previous frame's reads of the buffer (fenced on the host) before this write
            buffer_barrier(cb, r, _any_access(), copy_write())
            v.vkCmdCopyBuffer(cb, staging.handle, r.handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0, size=size)])
            buffer_barrier(cb, r, copy_write(), _any_access())

    submit_once(ex, "graphics", record)  # waited for: the next frame's receive may reuse the staging buffers
