"""Skinned characters' logic states evaluated in a worker process (issue 18).

The logic thread of the renderer (``rgraph run --logic-hz``) would otherwise hold the GIL for
most of a tick (a thousand NumPy calls), and every C call of the render thread waits to take
it back. Here a child process (``python -m rgraph.scene.skin_worker``, its own interpreter and
GIL) evaluates every skinned mesh's state (``Animator.state``, ``threads`` chunks of
characters) into one of two buffers of shared memory (a memfd, mapped by both); the parent
asks for tick ``k`` with 12 bytes on a pipe and gets 28 back when it is written. After
handing out tick ``k`` it asks for ``k + 1`` at once (into the other buffer), so the worker
computes while the logic thread sleeps until the next tick is due; the logic thread's work
per tick is then two small pipe messages and one 4 MiB copy out of the buffer (NumPy's copy
releases the GIL).

Messages: parent -> child ``<qi`` (tick, buffer; tick -1 stops); child -> parent ``<qidd``
(tick, buffer or -1 with an error text of ``<i`` length after it, wall and CPU seconds of the
evaluation). The child exits at a stop message or when its stdin closes (the parent died); its
errors come back as ``SkinWorkerError`` with the child's traceback, and so does its death.
"""

from __future__ import annotations

import mmap
import os
import pickle
import select
import statistics
import struct
import subprocess
import sys
import tempfile
import time
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np

REQUEST = struct.Struct("<qi")
REPLY = struct.Struct("<qidd")
LENGTH = struct.Struct("<i")
BUFFERS = 2
READY, FAILED = -2, -1  # reply "buffer" values: the child started; a tick (or the start) failed


class SkinWorkerError(RuntimeError):
    """The worker failed (its traceback in the message) or exited."""


def _read_exactly(stream: IO[bytes], n: int) -> bytes:
    """``n`` bytes from a (raw or buffered) stream; EOFError at its end."""
    parts, got = [], 0
    while got < n:
        data = stream.read(n - got)
        if not data:
            raise EOFError
        parts.append(data)
        got += len(data)
    return b"".join(parts)


def _write_all(stream: IO[bytes], data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[stream.write(view):]
    stream.flush()


def _shared_file(size: int) -> int:
    """A file descriptor of ``size`` bytes of memory (memfd; an unlinked temporary file elsewhere)."""
    if hasattr(os, "memfd_create"):
        fd = os.memfd_create("rgraph-skin", os.MFD_CLOEXEC)
    else:  # pragma: no cover - not Linux
        handle = tempfile.TemporaryFile()
        fd = os.dup(handle.fileno())
        handle.close()
    os.ftruncate(fd, size)
    return fd


class SkinWorker:
    """States of ``animators`` (every skinned mesh, concatenated in this order) at logic rate
    ``hz``, evaluated in a child process; see the module docstring. ``fetch(tick)`` returns a
    read-only uint8 view of the buffer that holds state ``tick``, valid until the next fetch."""

    def __init__(self, animators: Sequence[Any], hz: float, threads: int = 1, timeout: float = 120.0) -> None:
        self.sizes = [a.bones * a.characters * 16 for a in animators]
        self.nbytes = max(sum(self.sizes), 1)
        self.hz, self.threads, self.timeout = float(hz), max(1, int(threads)), timeout
        self._fd = _shared_file(BUFFERS * self.nbytes)
        self._map = mmap.mmap(self._fd, BUFFERS * self.nbytes)
        whole = np.frombuffer(self._map, dtype=np.uint8)
        self._views = [whole[k * self.nbytes:(k + 1) * self.nbytes] for k in range(BUFFERS)]
        for view in self._views:
            view.flags.writeable = False
        self._pending: tuple[int, int] | None = None  # (tick, buffer) being evaluated
        self._held: tuple[int, int] | None = None  # (tick, buffer) the last fetch returned
        self.compute_s: list[float] = []  # the worker's wall seconds per evaluated tick
        self.compute_cpu_s: list[float] = []  # its CPU seconds (every thread of the process)
        self.wait_s: list[float] = []  # the caller's wait in fetch per tick
        root = str(Path(__file__).resolve().parents[2])  # the rgraph checkout or site-packages this runs from
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}
        self._proc = subprocess.Popen([sys.executable, "-m", "rgraph.scene.skin_worker", str(self._fd)],
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE, pass_fds=(self._fd,), env=env,
                                      bufsize=0)
        self.pid = self._proc.pid
        try:
            payload = pickle.dumps((list(animators), self.hz, self.threads, self.nbytes), pickle.HIGHEST_PROTOCOL)
            self._send_raw(LENGTH.pack(len(payload)) + payload)
            tick, status, _w, _c = self._reply()
            if status != READY:
                raise SkinWorkerError(f"skinning worker: unexpected first reply {(tick, status)}")
        except BaseException:
            self.close()
            raise

    # ----------------------------------------------------------------- the caller (logic thread)
    def fetch(self, tick: int) -> np.ndarray:
        """State ``tick`` (bytes of every mesh's (B, C, 8) float16 state, concatenated);
        asks for ``tick + 1`` before returning."""
        if self._held is not None and self._held[0] == tick:
            return self._views[self._held[1]]
        t0 = time.perf_counter()
        if self._pending is not None and self._pending[0] != tick:
            self._finish()  # a prefetch of another tick: let it end, drop it
        if self._pending is None:
            buffer = 0 if self._held is None else 1 - self._held[1]
            self._request(tick, buffer)
        buffer = self._finish()
        self.wait_s.append(time.perf_counter() - t0)
        self._held = (tick, buffer)
        self._request(tick + 1, 1 - buffer)
        for series in (self.wait_s, self.compute_s, self.compute_cpu_s):
            if len(series) > 4096:
                del series[:2048]
        return self._views[buffer]

    def stats(self) -> dict[str, Any]:
        """Medians in microseconds: the worker's evaluation (wall, CPU) and the caller's wait."""
        def median_us(values: list[float]) -> float | None:
            return statistics.median(values) * 1e6 if values else None

        return {"worker": "process", "pid": self.pid, "threads": self.threads, "ticks": len(self.compute_s),
                "tick_us": median_us(self.compute_s), "tick_cpu_us": median_us(self.compute_cpu_s),
                "wait_us": median_us(self.wait_s)}

    @property
    def alive(self) -> bool:
        return self._proc.poll() is None

    def close(self, timeout: float = 5.0) -> None:
        """Stop the child (a stop message, then terminate after ``timeout``) and free the
        memory; idempotent."""
        proc = self._proc if hasattr(self, "_proc") else None
        if proc is not None and proc.poll() is None:
            try:
                self._send_raw(REQUEST.pack(-1, 0))
                proc.stdin.close()
            except (BrokenPipeError, OSError, ValueError):
                pass
            try:
                proc.wait(timeout)
            except subprocess.TimeoutExpired:
                proc.terminate()
                proc.wait(timeout)
        if proc is not None:
            for stream in (proc.stdin, proc.stdout):
                if stream is not None and not stream.closed:
                    stream.close()
        self._pending = self._held = None
        if getattr(self, "_map", None) is not None:
            self._views = []
            try:
                self._map.close()
            except BufferError:  # a caller still holds a view: the mapping goes with it
                pass
            self._map = None
        if getattr(self, "_fd", None) is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> SkinWorker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ----------------------------------------------------------------- pipe
    def _send_raw(self, data: bytes) -> None:
        try:
            _write_all(self._proc.stdin, data)
        except (BrokenPipeError, OSError) as exc:
            raise SkinWorkerError(f"skinning worker exited ({self._exit()})") from exc

    def _request(self, tick: int, buffer: int) -> None:
        self._send_raw(REQUEST.pack(tick, buffer))
        self._pending = (tick, buffer)

    def _reply(self) -> tuple[int, int, float, float]:
        stdout = self._proc.stdout
        ready, _, _ = select.select([stdout], [], [], self.timeout)  # blocks without the GIL
        if not ready:
            raise SkinWorkerError(f"skinning worker: no reply in {self.timeout:g} s")
        try:
            tick, status, wall, cpu = REPLY.unpack(_read_exactly(stdout, REPLY.size))
            if status == FAILED:
                (length,) = LENGTH.unpack(_read_exactly(stdout, LENGTH.size))
                text = _read_exactly(stdout, length).decode("utf-8", "replace")
                raise SkinWorkerError(f"skinning worker failed at tick {tick}:\n{text.rstrip()}")
        except EOFError:
            raise SkinWorkerError(f"skinning worker exited ({self._exit()})") from None
        return tick, status, wall, cpu

    def _finish(self) -> int:
        """Wait for the pending request; the buffer it wrote."""
        assert self._pending is not None
        want, buffer = self._pending
        self._pending = None
        tick, got, wall, cpu = self._reply()
        if (tick, got) != (want, buffer):
            raise SkinWorkerError(f"skinning worker: reply {(tick, got)} to request {(want, buffer)}")
        self.compute_s.append(wall)
        self.compute_cpu_s.append(cpu)
        return buffer

    def _exit(self) -> str:
        try:
            code = self._proc.wait(1.0)
        except subprocess.TimeoutExpired:
            return "still running, not answering"
        return f"exit code {code}"


# --------------------------------------------------------------------- the child
def serve(fd: int, stdin: IO[bytes], stdout: IO[bytes]) -> int:
    """The worker's loop (``python -m rgraph.scene.skin_worker FD``)."""
    def reply(tick: int, status: int, wall: float = 0.0, cpu: float = 0.0, text: str = "") -> None:
        data = REPLY.pack(tick, status, wall, cpu)
        if status == FAILED:
            raw = text.encode()
            data += LENGTH.pack(len(raw)) + raw
        _write_all(stdout, data)

    try:
        (length,) = LENGTH.unpack(_read_exactly(stdin, LENGTH.size))
        animators, hz, threads, nbytes = pickle.loads(_read_exactly(stdin, length))
        shared = mmap.mmap(fd, BUFFERS * nbytes)
        os.close(fd)
        whole = np.frombuffer(shared, dtype=np.uint8)
        outs = []  # per buffer: each animator's (B, C, 8) uint16 view
        for k in range(BUFFERS):
            views, offset = [], k * nbytes
            for a in animators:
                size = a.bones * a.characters * 16
                views.append(whole[offset:offset + size].view(np.uint16).reshape(a.bones, a.characters, 8))
                offset += size
            outs.append(views)
    except EOFError:
        return 0
    except BaseException:  # noqa: BLE001 -- reported to the parent
        reply(0, FAILED, text=traceback.format_exc())
        return 1
    reply(0, READY)
    while True:
        try:
            tick, buffer = REQUEST.unpack(_read_exactly(stdin, REQUEST.size))
        except EOFError:  # the parent closed the pipe or died
            return 0
        if tick < 0:
            return 0
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            for a, out in zip(animators, outs[buffer], strict=True):
                a.state(tick, hz, threads, out=out)
        except Exception:  # noqa: BLE001 -- reported to the parent, which decides
            reply(tick, FAILED, text=traceback.format_exc())
            continue
        reply(tick, buffer, time.perf_counter() - t0, time.process_time() - c0)


def main() -> int:
    """The child's entry: the protocol on the original stdout; anything printed goes to stderr."""
    replies = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    return serve(int(sys.argv[1]), sys.stdin.buffer, replies)


if __name__ == "__main__":
    sys.exit(main())
