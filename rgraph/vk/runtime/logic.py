"""Scene logic on its own thread at a fixed rate (``rgraph run --logic-hz HZ``).

The logic thread runs ``step(seconds)`` at scene time ``tick / hz`` on a fixed schedule (tick k
is due at ``anchor + k / hz`` on its clock) and publishes each result as a ``LogicState``; the
render thread (the frame loop) takes the last two states and interpolates between them with
``interpolation_alpha``: the frame shows scene time ``prev + alpha (cur - prev)``, one tick
behind the newest state, so motion stays smooth whatever the frame rate. The render thread
does only mapped-memory writes of what the logic computed, and submits.

A logic thread that falls more than ``max_catch_up`` ticks behind (a slow step, a loaded
machine) moves its schedule instead of bursting: those ticks count as ``late``, scene time
stays continuous. An exception in ``step`` stops the thread and is kept in ``error``; the
frame loop raises it (``rgraph.vk.errors.ExecutionError``). ``clock`` and ``wait`` are
injectable (tests drive time themselves); ``lock`` is held while a state is published (the
scene takes it to read a state and mark it in use in one step).

The thread runs between ``start`` and ``stop`` (the frame loop starts it per run of frames);
each start schedules the next tick one period later. ``stats`` reports the rate the schedule
kept, ``measured_hz``: the ticks run on the thread over the time from each start to that run's
last tick (on time, exactly ``hz``: a late tick lengthens it), the ticks that were due but had
not run when a run stopped (``behind_at_stop``), and each tick's delay past its due time.
``ticks_per_running_second`` (the ticks after tick 0 over the time running, start to stop) is
what ``measured_hz`` was before session 11: it also counts, per run, the part period before
the stop that no tick could fill (short runs read low: 52.8-56.5 Hz of 60 in 0.6 s of
frames cut into eight runs, none late).
"""

from __future__ import annotations

import math
import statistics
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class LogicState:
    tick: int
    seconds: float  # scene time: tick / hz
    wall: float  # the logic clock when the state was published
    value: Any  # what step returned (the scene's deformable positions)


def interpolation_alpha(now: float, published: float, hz: float) -> float:
    """How far (0..1) a frame at ``now`` is from the previous state to the one published at
    ``published``: a tick period after publication it reaches the newest state."""
    alpha = (now - published) * hz
    if not math.isfinite(alpha) or alpha <= 0.0:
        return 0.0
    return min(alpha, 1.0)


class LogicThread:
    """See the module docstring. ``start`` computes tick 0 on the caller's thread (a frame
    always has two states), then ticks on a daemon thread until ``stop``."""

    def __init__(self, step: Callable[[float], Any], hz: float, *, clock: Callable[[], float] = time.perf_counter,
                 wait: Callable[[float], None] | None = None, max_catch_up: int = 4,
                 lock: Any = None) -> None:
        if not hz > 0 or not math.isfinite(hz):
            raise ValueError(f"logic rate must be a positive number of Hz, not {hz}")
        self.step = step
        self.hz = float(hz)
        self.clock = clock
        self.max_catch_up = max_catch_up
        self.lock = lock if lock is not None else threading.Lock()  # held while a state is published
        self._stop = threading.Event()
        self._wait = wait if wait is not None else self._stop.wait
        self._thread: threading.Thread | None = None
        self._states: tuple[LogicState, LogicState] | None = None
        self.error: BaseException | None = None
        self.tick = 0  # the next tick to run
        self.ticks = 0  # ticks run (tick 0 included)
        self.late = 0  # ticks the schedule skipped past
        self.tick_seconds: list[float] = []  # each tick's step time (wall, the logic thread)
        self._anchor = 0.0
        self._started_at = 0.0
        self._running_seconds = 0.0
        self._last_tick_at: float | None = None  # this run's last tick on the thread (its clock)
        self._thread_ticks = 0  # ticks run on the thread (tick 0 of start excluded)
        self._covered_seconds = 0.0  # per run: start to its last tick on the thread
        self.runs = 0  # starts of the thread
        self.behind_at_stop = 0  # ticks due, not run, when a run stopped
        self.tick_delays: list[float] = []  # each thread tick's start past its due time

    # ----------------------------------------------------------------- render thread
    def latest(self) -> tuple[LogicState, LogicState]:
        """(previous, newest) state: one tuple, replaced whole by the logic thread."""
        states = self._states
        assert states is not None, "LogicThread.start first"
        return states

    def published(self) -> tuple[LogicState, ...]:
        """The states a frame may still take (none before tick 0)."""
        return self._states or ()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def start(self) -> None:
        if self.running:
            return
        self._stop.clear()
        self.error = None
        now = self.clock()
        if self._states is None:
            self._run_tick(now)
            first = self._states[1]  # type: ignore[index]
            self._states = (first, first)
        self._anchor = now - (self.tick - 1) / self.hz  # the next tick is due one period from now
        self._started_at = now
        self._last_tick_at = None
        self.runs += 1
        self._thread = threading.Thread(target=self._loop, name="rgraph-logic", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 10.0) -> None:
        """Stop and join the thread (idempotent); the states stay readable."""
        asked = self.clock()
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None:
            thread.join(timeout)
            self._running_seconds += self.clock() - self._started_at
            if self._last_tick_at is not None:
                self._covered_seconds += self._last_tick_at - self._started_at
            due = math.floor((asked - self._anchor) * self.hz) + 1  # ticks 0 .. due - 1 were due
            self.behind_at_stop += max(0, due - self.tick)

    def stats(self) -> dict[str, Any]:
        """What ``rgraph run --logic-hz`` reports (timings ``logic``)."""
        now = self.clock()
        ran = self._running_seconds + (now - self._started_at if self.running else 0.0)
        covered = self._covered_seconds + (self._last_tick_at - self._started_at
                                           if self.running and self._last_tick_at is not None else 0.0)
        return {"hz": self.hz, "ticks": self.ticks, "late_ticks": self.late,
                "measured_hz": self._thread_ticks / covered if covered > 0 else None,
                "ticks_per_running_second": (self.ticks - 1) / ran if ran > 0 and self.ticks > 1 else None,
                "runs": self.runs, "behind_at_stop": self.behind_at_stop,
                "tick_delay_us": statistics.median(self.tick_delays) * 1e6 if self.tick_delays else None,
                "tick_us": statistics.median(self.tick_seconds) * 1e6 if self.tick_seconds else None}

    # ----------------------------------------------------------------- logic thread
    def _run_tick(self, now: float) -> None:
        t0 = time.perf_counter()
        value = self.step(self.tick / self.hz)
        self.tick_seconds.append(time.perf_counter() - t0)
        if len(self.tick_seconds) > 4096:
            del self.tick_seconds[:2048]
        state = LogicState(self.tick, self.tick / self.hz, self.clock(), value)
        with self.lock:
            prev = self._states[1] if self._states is not None else state
            self._states = (prev, state)
        self.tick += 1
        self.ticks += 1

    def _loop(self) -> None:
        try:
            while not self._stop.is_set():
                now = self.clock()
                due = self._anchor + self.tick / self.hz
                if now < due:
                    self._wait(due - now)
                    continue
                behind = int((now - due) * self.hz)
                if behind > self.max_catch_up:  # move the schedule rather than burst
                    self.late += behind
                    self._anchor += behind / self.hz
                self.tick_delays.append(now - self._anchor - self.tick / self.hz)
                if len(self.tick_delays) > 4096:
                    del self.tick_delays[:2048]
                self._run_tick(now)
                self._thread_ticks += 1
                self._last_tick_at = now
        except BaseException as exc:  # noqa: BLE001 -- kept for the render thread to raise
            self.error = exc
