"""The skinning worker process (rgraph.scene.skin_worker): its states equal the reference,
concatenated over meshes, for consecutive ticks (prefetched), repeats and jumps; its errors and
its death come back as one SkinWorkerError; it exits at close and when its parent's pipe closes."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

from rgraph.scene.animation import Animator
from rgraph.scene.character import build_rig
from rgraph.scene.skin_worker import SkinWorker, SkinWorkerError


def reference(animators, tick, hz):
    return np.concatenate([a.reference_state(tick, hz).view(np.uint8).reshape(-1) for a in animators])


def gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def test_worker_states_equal_the_reference_and_it_exits_at_close():
    animators = [Animator(build_rig(64), 70, seed=1), Animator(build_rig(9), 3, seed=2, amplitude=2.0)]
    with SkinWorker(animators, 30.0, threads=2) as worker:
        assert worker.nbytes == (64 * 70 + 9 * 3) * 16
        for tick in (0, 1, 2, 3, 3, 10, 4, 5):  # prefetched, repeated, jumped ahead and back
            got = worker.fetch(tick)
            assert not got.flags.writeable
            assert np.array_equal(got, reference(animators, tick, 30.0)), tick
        stats = worker.stats()
        assert stats["worker"] == "process" and stats["threads"] == 2 and stats["ticks"] >= 7
        assert stats["tick_us"] > 0 and stats["wait_us"] >= 0
        pid = worker.pid
    assert not worker.alive and worker._proc.returncode == 0 and gone(pid)
    worker.close()  # idempotent


def test_worker_errors_come_back_with_the_childs_traceback():
    with SkinWorker([Animator(build_rig(8), 2)], float("nan")) as worker:
        with pytest.raises(SkinWorkerError, match="(?s)failed at tick 0.*ValueError: scene time must be finite"):
            worker.fetch(0)
        assert worker.alive  # a failed tick does not end the worker


def test_a_dead_worker_is_an_error_and_a_closed_pipe_ends_it():
    anim = Animator(build_rig(8), 2)
    worker = SkinWorker([anim], 60.0)
    try:
        assert np.array_equal(worker.fetch(0), reference([anim], 0, 60.0))
        os.kill(worker.pid, signal.SIGKILL)
        worker._proc.wait(10)
        with pytest.raises(SkinWorkerError, match="exited"):
            worker.fetch(7)
    finally:
        worker.close()
    orphan = SkinWorker([anim], 60.0)
    try:
        orphan._proc.stdin.close()  # what the parent's death does to the pipe
        assert orphan._proc.wait(30) == 0
    finally:
        orphan.close()
