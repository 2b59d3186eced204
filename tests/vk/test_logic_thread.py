"""Scene logic on its own thread (rgraph.vk.runtime.logic, ``rgraph run --logic-hz``).

The schedule is tested with an injectable clock (exact, no timing assertions); the real clock
only with a wide, one-sided margin. End to end: surgery on lavapipe under validation with the
logic thread, a failing logic step and a KeyboardInterrupt in the render loop.
"""

from __future__ import annotations

import json
import math
import threading
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import rgraph
from rgraph.cli import main
from rgraph.vk.errors import ExecutionError
from rgraph.vk.runtime.logic import LogicThread, interpolation_alpha


class FakeClock:
    """Time that moves only when the logic thread waits (by exactly what it asks for)."""

    def __init__(self) -> None:
        self.t = 1000.0
        self.lock = threading.Lock()

    def now(self) -> float:
        with self.lock:
            return self.t

    def advance(self, dt: float) -> None:
        with self.lock:
            self.t += dt
        time.sleep(0)  # let the render thread run


def run_until(logic: LogicThread, ticks: int, timeout: float = 20.0) -> None:
    logic.start()
    deadline = time.monotonic() + timeout
    while logic.ticks < ticks and logic.error is None and time.monotonic() < deadline:
        time.sleep(0.001)
    logic.stop()


@given(st.floats(allow_nan=True, allow_infinity=True), st.floats(allow_nan=True, allow_infinity=True),
       st.floats(min_value=1e-3, max_value=1e4))
def test_alpha_is_always_in_0_1(now, published, hz):
    a = interpolation_alpha(now, published, hz)
    assert 0.0 <= a <= 1.0 and not math.isnan(a)


def test_alpha_rises_from_the_previous_to_the_newest_state_in_one_period():
    assert interpolation_alpha(10.0, 10.0, 60) == 0.0
    assert interpolation_alpha(10.0 + 0.5 / 60, 10.0, 60) == pytest.approx(0.5)
    assert interpolation_alpha(11.0, 10.0, 60) == 1.0
    assert interpolation_alpha(9.0, 10.0, 60) == 0.0


def test_ticks_follow_the_fixed_schedule_with_an_injected_clock():
    clock = FakeClock()
    seen: list[tuple[float, float]] = []
    logic = LogicThread(lambda s: seen.append((s, clock.now())) or s, 60.0, clock=clock.now, wait=clock.advance)
    start = clock.now()
    run_until(logic, 120)
    assert logic.error is None and logic.late == 0 and not logic.running
    assert len(seen) == logic.ticks >= 120
    for k, (seconds, at) in enumerate(seen):
        assert seconds == k / 60.0  # scene time is the tick count, never the wall clock
        assert at == pytest.approx(start + k / 60.0, abs=1e-9)  # tick k ran when it was due
    prev, cur = logic.latest()
    assert (prev.tick, cur.tick) == (logic.ticks - 2, logic.ticks - 1) and cur.value == cur.seconds
    # the measured rate (ticks over the injected time) is the requested one
    assert logic.stats()["measured_hz"] == pytest.approx(60.0, rel=0.05)


def test_restarts_keep_the_rate_and_the_old_figure_counts_the_part_periods():
    """Runs of a few ticks each (the benchmarks' warm-up batches): every due tick runs, so the
    kept rate is the requested one; ticks over the running time (start to stop) reads lower,
    since each run's first tick is due a period after its start."""
    clock = FakeClock()
    logic = LogicThread(lambda s: s, 60.0, clock=clock.now, wait=clock.advance)
    for _ in range(8):
        run_until(logic, logic.ticks + 3)
        clock.advance(0.1)  # stopped: no schedule
    stats = logic.stats()
    assert stats["runs"] == 8 and logic.late == 0
    assert stats["measured_hz"] == pytest.approx(60.0, rel=1e-9)
    assert stats["behind_at_stop"] <= 8  # at most a tick due at the very moment of a stop
    assert stats["tick_delay_us"] == pytest.approx(0.0, abs=1e-3)  # the fake clock is never late
    running = stats["ticks_per_running_second"]
    assert running is not None and running < 60.0


def test_a_lagging_schedule_reads_low_and_counts_ticks_behind_at_stop():
    """Each step takes 2.5 periods: ticks run back to back, the kept rate is hz / 2.5 and the
    ticks due but not run when the thread stops are counted."""
    clock = FakeClock()

    def slow(seconds: float) -> float:
        if seconds > 0:
            clock.advance(2.5 / 60)
        return seconds

    logic = LogicThread(slow, 60.0, clock=clock.now, wait=clock.advance, max_catch_up=10**6)
    run_until(logic, 20)
    stats = logic.stats()
    assert logic.late == 0
    assert stats["measured_hz"] == pytest.approx(60.0 / 2.5, rel=0.1)
    assert stats["behind_at_stop"] >= 10
    assert stats["tick_delay_us"] > 1e4


def test_a_slow_step_moves_the_schedule_instead_of_bursting():
    clock = FakeClock()

    def slow(seconds: float) -> float:
        if round(seconds * 30) == 10:  # tick 10 takes 20 periods
            clock.advance(20 / 30)
        return seconds

    logic = LogicThread(slow, 30.0, clock=clock.now, wait=clock.advance, max_catch_up=4)
    run_until(logic, 40)
    assert logic.error is None
    assert logic.late >= 15  # skipped, not run back to back
    assert [s.tick for s in logic.latest()] == [logic.ticks - 2, logic.ticks - 1]


def test_real_clock_rate_with_a_wide_margin():
    logic = LogicThread(lambda s: None, 200.0)
    t0 = time.perf_counter()
    logic.start()
    time.sleep(0.5)
    logic.stop()
    elapsed = time.perf_counter() - t0
    # never ahead of the schedule; behind only by a wide margin on a loaded machine
    assert 0.2 * elapsed * 200 <= logic.ticks <= elapsed * 200 + 2


def test_an_error_in_the_step_stops_the_thread_and_is_kept():
    clock = FakeClock()

    def step(seconds: float) -> None:
        if seconds >= 5 / 60:
            raise ValueError("boom")

    logic = LogicThread(step, 60.0, clock=clock.now, wait=clock.advance)
    run_until(logic, 100)
    assert isinstance(logic.error, ValueError) and not logic.running and logic.ticks == 5


def test_bad_rates_are_refused():
    for hz in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError):
            LogicThread(lambda s: None, hz)


# ----------------------------------------------------------------------------- on the device


def test_rgraph_run_logic_hz_is_validation_clean_and_reports_the_render_thread(capsys):
    rc = main(["run", "surgery", "--size", "32x24", "--frames", "8", "--validate", "--logic-hz", "60", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert rc == 0 and doc["ok"] and doc["validation"]["messages"] == []
    t = doc["timings"]
    assert t["frames"] == 8  # every frame submitted and timed: none lost
    render, logic = t["render_thread"], t["logic"]
    assert render["cpu_us_per_frame"] > 0 and render["update_us"] > 0
    assert logic["hz"] == 60 and logic["ticks"] >= 1 and logic["late_ticks"] >= 0
    lo, hi = logic["alpha_range"]
    assert 0.0 <= lo <= hi <= 1.0


def test_logic_states_reach_the_gpu_interpolated():
    """The logic thread writes each tick into a free ring slot; a frame's header names the two
    slots it mixes and alpha (0..1); slots in use by a frame are never overwritten."""
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        plan = rgraph.compile("surgery", size=(32, 24), device=gpu)
        exe = gpu.load(plan, logic_hz=240)
        exe.run(6)
        scene = exe.executor.scene_gpu
        deform = scene.deform
        s = (exe.executor.frames_done - 1) % 2
        f, u = deform.header_views[s]
        alpha, prev_slot, cur_slot = float(f[0]), int(u[1]), int(u[2])
        assert 0.0 <= alpha <= 1.0 and (prev_slot, cur_slot) == deform.in_use[s]
        prev_tick, cur_tick = scene.ticks_taken[s]
        assert prev_tick <= cur_tick <= exe.executor.logic.latest()[1].tick
        (part,) = deform.parts
        for slot, tick in ((prev_slot, prev_tick), (cur_slot, cur_tick)):
            expected = part.deformer.positions(tick / 240)
            np.testing.assert_allclose(deform.slots[slot], expected, rtol=0, atol=1e-7)
        busy = [x for pair in deform.in_use for x in pair]
        assert len(set(busy) | {st.value[0] for st in exe.executor.logic.published()}) <= 6
        assert [str(m) for m in exe.close()] == []


def test_failing_logic_and_interrupts_shut_down_cleanly(monkeypatch):
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        plan = rgraph.compile("surgery", size=(32, 24), device=gpu)
        exe = gpu.load(plan, logic_hz=1000)
        logic = exe.executor.logic

        real_step = logic.step

        def broken(seconds: float):
            if seconds > 2 / 1000:
                raise RuntimeError("logic step failed")
            return real_step(seconds)

        logic.step = broken
        with pytest.raises(ExecutionError, match="logic thread failed.*logic step failed"):
            exe.run(10_000)  # fails long before: the thread ticks at 1 kHz
        assert not logic.running and exe.executor.frames_done == 0
        assert [str(m) for m in exe.close()] == []

        exe = gpu.load(plan, logic_hz=60)
        def broken_at_once(seconds: float):
            raise RuntimeError("logic step failed")

        exe.executor.logic.step = broken_at_once  # at tick 0, before the first frame
        with pytest.raises(ExecutionError, match="frame 0: the logic thread failed"):
            exe.run(3)
        assert [str(m) for m in exe.close()] == []

        exe = gpu.load(plan, logic_hz=60)
        scene = exe.executor.scene_gpu
        real = scene.frame_update  # the per-frame update the frame loop takes for a run

        def interrupting() -> object:
            update = real()

            def interrupted(frame: int, frame_set: int) -> None:
                if frame == 3:
                    raise KeyboardInterrupt
                update(frame, frame_set)

            return interrupted

        monkeypatch.setattr(scene, "frame_update", interrupting)
        exe.executor.scene_gpu = scene
        with pytest.raises(KeyboardInterrupt):
            exe.run(50)
        assert not exe.executor.logic.running
        assert [str(m) for m in exe.close()] == []
        assert [str(m) for m in gpu.close()] == []


@pytest.mark.parametrize("value", ["0", "-5", "nan", "fast", "1e9"])
def test_bad_logic_rates_are_one_line_errors(value, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["run", "surgery", "--logic-hz", value])
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2 and "--logic-hz" in err[-1] and "Traceback" not in "".join(err)


def test_without_logic_positions_are_written_ahead_into_free_slots():
    """No logic thread: each frame's positions are written right after the previous frame's
    submits (DeformGPU.prepare) into an ahead slot no frame in flight reads; each of the last
    two frames' headers names the slot holding its own time's positions (alpha 1), and the
    next frame's prepared slot is a third one."""
    from rgraph.vk.scene_deform import AHEAD_SLOTS

    with rgraph.open_device(validate=True, verbose=False) as gpu:
        plan = rgraph.compile("surgery", size=(32, 24), device=gpu)
        exe = gpu.load(plan)
        exe.run(6)
        ex = exe.executor
        scene, deform = ex.scene_gpu, ex.scene_gpu.deform
        (part,) = deform.parts
        done = ex.frames_done
        shown = []
        for frame in (done - 2, done - 1):
            f, u = deform.header_views[frame % 2]
            assert float(f[0]) == 1.0 and int(u[1]) == int(u[2])
            slot = int(u[2])
            assert slot in AHEAD_SLOTS
            content = frame - ex.frame_origin
            expected = part.deformer.positions(scene.data.seconds(content))
            np.testing.assert_allclose(deform.slots[slot], expected, rtol=0, atol=1e-6)
            shown.append(slot)
        ahead = deform._ahead
        assert ahead is not None and ahead[0] == done - ex.frame_origin and ahead[2] not in shown
        assert len(set(shown)) == 2
        assert [str(m) for m in exe.close()] == []
