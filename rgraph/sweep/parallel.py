"""Independent tasks in worker processes, one process per task: local spawned processes
(``--workers N``) or Ray tasks (``--ray [ADDRESS]``).

:class:`Executor` owns the semantics both backends share: at most ``slots`` tasks run at
once, results stream back in completion order, a task that raised or whose worker was lost
(killed, crashed) is retried once, then reported as an :class:`Outcome` with its error; no
failure stops the others. A backend only starts a task, waits for some to finish and cancels.
Ray is imported only by :class:`RayBackend`.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import multiprocessing.connection
import os
import traceback
from collections import deque
from collections.abc import Callable, Hashable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Protocol

Status = str  # "ok" | "error" (the task raised) | "lost" (its worker died)


@dataclass
class Outcome:
    """One task's result: ``value`` when ``error`` is None; ``attempts`` counts tries."""

    key: Hashable
    value: Any = None
    error: str | None = None
    attempts: int = 1

    @property
    def ok(self) -> bool:
        return self.error is None


def describe(exc: BaseException) -> str:
    """One line: the exception and where it was raised (the innermost frame)."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = f" (at {os.path.basename(frames[-1].filename)}:{frames[-1].lineno})" if frames else ""
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}{where}"


def call(fn: Callable[[Any], Any], arg: Any) -> tuple[Status, Any]:
    """Run ``fn(arg)`` inside a worker: ``("ok", value)`` or ``("error", description)``."""
    try:
        return "ok", fn(arg)
    except BaseException as exc:  # noqa: BLE001 - every failure is reported with its task
        return "error", describe(exc)


class Backend(Protocol):
    slots: int | None  # tasks running at once (None: the backend's scheduler queues them)
    description: str

    def start(self, fn: Callable[[Any], Any], arg: Any) -> Hashable: ...

    def wait(self, handles: list[Hashable]) -> list[tuple[Hashable, Status, Any]]: ...

    def cancel(self, handles: list[Hashable]) -> None: ...

    def close(self) -> None: ...


class Executor:
    """Runs tasks on a backend with retry and per-task reporting."""

    def __init__(self, backend: Backend, *, retries: int = 1) -> None:
        self.backend, self.retries = backend, retries

    @property
    def description(self) -> str:
        return self.backend.description

    @property
    def timing_lock(self) -> str | None:
        """The file its local workers lock around timed frames (None: they do not share one machine)."""
        return getattr(self.backend, "timing_lock", None)

    def run(self, fn: Callable[[Any], Any], items: Iterable[tuple[Hashable, Any]]) -> Iterator[Outcome]:
        """``fn(arg)`` for every ``(key, arg)``, each in a fresh worker process; yields as
        tasks finish. ``items`` is read only when a slot is free (all at once without a slot
        limit). ``fn`` must be importable (module level). Closing the iterator early cancels
        the tasks still running."""
        source = iter(items)  # taken lazily: an item may depend on results that came back
        queue: deque[tuple[Hashable, Any, int, list[str]]] = deque()  # retries, first
        running: dict[Hashable, tuple[Hashable, Any, int, list[str]]] = {}
        slots = self.backend.slots
        exhausted = False
        try:
            while True:
                while slots is None or len(running) < slots:
                    if not queue and not exhausted:
                        item = next(source, None)
                        if item is None:
                            exhausted = True
                        else:
                            queue.append((item[0], item[1], 1, []))
                    if not queue:
                        break
                    task = queue.popleft()
                    running[self.backend.start(fn, task[1])] = task
                if not running:
                    break
                for handle, status, value in self.backend.wait(list(running)):
                    key, arg, attempt, errors = running.pop(handle)
                    if status == "ok":
                        yield Outcome(key, value, None, attempt)
                    elif attempt <= self.retries:
                        queue.appendleft((key, arg, attempt + 1, [*errors, str(value)]))  # retried first
                    else:
                        history = "; ".join(f"attempt {i + 1}: {e}" for i, e in enumerate([*errors, str(value)]))
                        yield Outcome(key, None, history, attempt)
        finally:
            if running:
                self.backend.cancel(list(running))

    def close(self) -> None:
        self.backend.close()

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# ------------------------------------------------------------------ local processes
def _answer(conn: Any, result: Any) -> None:
    """Send :func:`call`'s ``result`` back, or an error naming why it could not be sent."""
    try:
        conn.send(result)
    except Exception as exc:  # noqa: BLE001 - e.g. an unpicklable result
        conn.send(("error", f"result could not be sent back: {describe(exc)}"))


def _child_main(conn: Any, fn: Callable[[Any], Any], arg: Any) -> None:
    _answer(conn, call(fn, arg))
    conn.close()


def _serve(conn: Any, tasks: int) -> None:
    """A long-lived worker: up to ``tasks`` ``(fn, arg)`` from ``conn``, each answered with
    :func:`call`'s result, then exit (a spawned process exits through ``sys.exit``, so its
    ``atexit`` handlers run: e.g. a device kept open across tasks is closed)."""
    for _ in range(tasks):
        try:
            job = conn.recv()
        except EOFError:
            break
        if job is None:
            break
        _answer(conn, call(*job))
    conn.close()


@dataclass(eq=False)
class _Worker:
    process: Any
    conn: Any
    done: int = 0


class ProcessBackend:
    """``workers`` spawned processes at a time. ``tasks_per_worker`` 1 (default): each runs one
    task and exits (no state, no device, no driver instance outlives its task); K > 1: a
    worker takes up to K tasks one after another (saving the process's start: imports, a
    Vulkan instance and device, which a task may keep open for the next one), then exits
    and a fresh one takes its place. A worker that dies loses only its current task."""

    def __init__(self, workers: int, tasks_per_worker: int = 1) -> None:
        if workers < 1:
            raise ValueError(f"workers must be at least 1, got {workers}")
        if tasks_per_worker < 1:
            raise ValueError(f"tasks per worker must be at least 1, got {tasks_per_worker}")
        self.slots: int | None = workers
        self.tasks_per_worker = tasks_per_worker
        self.description = (f"{workers} local worker process{'es' if workers > 1 else ''}"
                            + (f" ({tasks_per_worker} settings each)" if tasks_per_worker > 1 else ""))
        self._ctx = multiprocessing.get_context("spawn")
        self._idle: list[_Worker] = []
        self.timing_lock: str | None = None  # workers lock it around timed frames (rgraph.sweep.remote)
        if workers > 1:
            import tempfile

            handle, self.timing_lock = tempfile.mkstemp(prefix="rgraph-timing-", suffix=".lock")
            os.close(handle)

    def start(self, fn: Callable[[Any], Any], arg: Any) -> _Worker:
        if self.tasks_per_worker == 1:
            recv, send = self._ctx.Pipe(duplex=False)
            process = self._ctx.Process(target=_child_main, args=(send, fn, arg), daemon=True)
            process.start()
            send.close()
            return _Worker(process, recv)
        worker = None
        while self._idle and worker is None:
            worker = self._idle.pop()
            if not worker.process.is_alive():  # died while idle
                worker.process.join()
                worker.conn.close()
                worker = None
        if worker is None:
            mine, theirs = self._ctx.Pipe(duplex=True)
            process = self._ctx.Process(target=_serve, args=(theirs, self.tasks_per_worker), daemon=True)
            process.start()
            theirs.close()
            worker = _Worker(process, mine)
        worker.conn.send((fn, arg))
        return worker

    def wait(self, handles: list[Hashable]) -> list[tuple[Hashable, Status, Any]]:
        workers: list[_Worker] = handles  # type: ignore[assignment]
        ready = set(multiprocessing.connection.wait(
            [w.conn for w in workers] + [w.process.sentinel for w in workers]))
        done = []
        for w in workers:
            if w.conn not in ready and w.process.sentinel not in ready:
                continue
            status, value = "lost", None
            try:
                if w.conn.poll():
                    status, value = w.conn.recv()
            except (EOFError, OSError):
                pass
            w.done += 1
            if status != "lost" and self.tasks_per_worker > 1 and w.done < self.tasks_per_worker:
                self._idle.append(w)  # it takes the next task
            else:
                w.process.join()
                w.conn.close()
            if status == "lost":
                code = w.process.exitcode
                value = (f"worker process killed by signal {-code}" if code is not None and code < 0
                         else f"worker process exited with code {code} without a result")
            done.append((w, status, value))
        return done

    def cancel(self, handles: list[Hashable]) -> None:
        for w in handles:
            w.process.kill()  # type: ignore[attr-defined]
            w.process.join()  # type: ignore[attr-defined]

    def close(self) -> None:
        """Let the idle workers exit."""
        for w in self._idle:
            try:
                w.conn.send(None)
            except OSError:
                pass
        for w in self._idle:
            w.process.join(timeout=30)
            if w.process.is_alive():
                w.process.kill()
                w.process.join()
            w.conn.close()
        self._idle = []
        if self.timing_lock:
            with contextlib.suppress(OSError):
                os.remove(self.timing_lock)
            self.timing_lock = None


# ------------------------------------------------------------------ Ray
def _ray_task(fn: Callable[[Any], Any], arg: Any) -> tuple[Status, Any]:
    return call(fn, arg)


def ray_resources(cluster: dict[str, float], gpu: bool | None) -> dict[str, float]:
    """What each task asks for: one GPU when the cluster has GPUs (or ``gpu`` says so), else
    one CPU."""
    use_gpu = cluster.get("GPU", 0) > 0 if gpu is None else gpu
    return {"num_gpus": 1} if use_gpu else {"num_cpus": 1}


class RayBackend:
    """Every task a Ray task in its own worker process (``max_calls=1``); Ray's own retries
    are off (``max_retries=0``) so :class:`Executor` retries exactly as for processes.
    ``address`` None: ``ray.init()`` (``RAY_ADDRESS`` or a new local cluster); an already
    initialized Ray is used as it is and left running."""

    def __init__(self, address: str | None = None, *, gpu: bool | None = None) -> None:
        import ray

        self._ray = ray
        self._owned = not ray.is_initialized()
        if self._owned:
            ray.init(address=address or None, include_dashboard=False)
        resources = ray_resources(ray.cluster_resources(), gpu)
        self.resources = resources
        self.slots: int | None = None
        self.description = (f"Ray ({address or 'local'}), one task per worker process, "
                            + ", ".join(f"{k}={v}" for k, v in resources.items()))
        self._remote = ray.remote(max_calls=1, max_retries=0, **resources)(_ray_task)

    def start(self, fn: Callable[[Any], Any], arg: Any) -> Hashable:
        return self._remote.remote(fn, arg)

    def wait(self, handles: list[Hashable]) -> list[tuple[Hashable, Status, Any]]:
        ready, _ = self._ray.wait(handles, num_returns=1)
        done = []
        for ref in ready:
            try:
                status, value = self._ray.get(ref)
            except Exception as exc:  # noqa: BLE001 - the worker died or the task was lost
                status, value = "lost", f"Ray task lost: {describe(exc)}"
            done.append((ref, status, value))
        return done

    def cancel(self, handles: list[Hashable]) -> None:
        for ref in handles:
            self._ray.cancel(ref, force=True)

    def close(self) -> None:
        if self._owned:
            self._ray.shutdown()


def assigned_gpu() -> int | None:
    """The GPU id Ray gave this task, or None outside a Ray GPU task."""
    import sys

    ray = sys.modules.get("ray")
    if ray is None or not ray.is_initialized():
        return None
    try:
        ids = ray.get_gpu_ids()
    except Exception:  # noqa: BLE001 - not in a task
        return None
    return int(ids[0]) if ids else None


def make_executor(workers: int | None = None, ray: str | None = None, *, use_ray: bool = False,
                  tasks_per_worker: int = 1) -> Executor | None:
    """The executor of ``--workers N`` (``tasks_per_worker``: settings per worker process) /
    ``--ray [ADDRESS]``; None for the one-process path."""
    if use_ray:
        return Executor(RayBackend(ray))
    if workers is not None:
        return Executor(ProcessBackend(workers, tasks_per_worker))
    return None
