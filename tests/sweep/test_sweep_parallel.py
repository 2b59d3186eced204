"""The executor's shared semantics (slots, streaming, retry once, per-task reports, cancel)
on a scripted in-process backend, and the local process backend on tiny tasks."""

from __future__ import annotations

import os

from rgraph.sweep.parallel import Executor, ProcessBackend, call, ray_resources


class Scripted:
    """A backend whose tasks finish one at a time, in submission order, with scripted
    statuses per (arg, attempt)."""

    def __init__(self, slots, script):
        self.slots, self.script, self.description = slots, script, "scripted"
        self.started, self.running, self.cancelled, self.peak = [], [], [], 0
        self.attempts: dict = {}

    def start(self, fn, arg):
        self.attempts[arg] = self.attempts.get(arg, 0) + 1
        handle = (arg, self.attempts[arg])
        self.started.append(handle)
        self.running.append(handle)
        self.peak = max(self.peak, len(self.running))
        return handle

    def wait(self, handles):
        handle = self.running.pop(0)
        status = self.script.get(handle, "ok")
        return [(handle, status, f"{handle[0]}!" if status == "ok" else f"{status} {handle[0]}")]

    def cancel(self, handles):
        self.cancelled += handles

    def close(self):
        pass


def test_retry_once_then_report_never_abort():
    backend = Scripted(2, {("a", 1): "lost", ("b", 1): "error", ("b", 2): "lost"})
    outcomes = list(Executor(backend).run(str, [(k, k) for k in "abcd"]))
    by_key = {o.key: o for o in outcomes}
    assert sorted(by_key) == ["a", "b", "c", "d"]
    assert by_key["a"].ok and by_key["a"].value == "a!" and by_key["a"].attempts == 2
    assert not by_key["b"].ok and by_key["b"].attempts == 2
    assert by_key["b"].error == "attempt 1: error b; attempt 2: lost b"
    assert by_key["c"].value == "c!" and by_key["c"].attempts == 1
    assert backend.peak == 2  # never more than the slots
    assert backend.started.index(("a", 2)) < backend.started.index(("d", 1))  # a retry goes first


def test_closing_early_cancels_what_runs():
    backend = Scripted(3, {})
    run = Executor(backend).run(str, [(k, k) for k in "abcde"])
    assert next(run).key == "a"
    run.close()
    assert sorted(h[0] for h in backend.cancelled) == ["b", "c"]  # d never started


def test_ray_resources():
    assert ray_resources({"CPU": 64, "GPU": 8}, None) == {"num_gpus": 1}
    assert ray_resources({"CPU": 2}, None) == {"num_cpus": 1}
    assert ray_resources({"CPU": 2, "GPU": 1}, False) == {"num_cpus": 1}


def test_call_reports_the_exception():
    assert call(int, "3") == ("ok", 3)
    status, text = call(int, "x")
    assert status == "error" and text.startswith("ValueError: invalid literal") and "(at " in text


def test_process_backend_one_process_per_task_and_lost_workers():
    executor = Executor(ProcessBackend(2), retries=0)
    got = {o.key: o for o in executor.run(os._exit, [("exit", 3)])}
    assert got["exit"].error == "attempt 1: worker process exited with code 3 without a result"
    pids = [o.value for o in Executor(ProcessBackend(2)).run(_pid, [(i, i) for i in range(3)])]
    assert len(set(pids)) == 3 and os.getpid() not in pids


def _pid(_arg):
    return os.getpid()


def test_a_ray_gpu_is_the_vulkan_gpu_of_that_ordinal():
    from rgraph.sweep.remote import gpu_device_index
    from rgraph.vk.device import PhysicalDeviceInfo

    devices = [PhysicalDeviceInfo(0, None, "llvmpipe", "cpu", (1, 4, 0)),
               PhysicalDeviceInfo(1, None, "H200 a", "discrete", (1, 4, 0)),
               PhysicalDeviceInfo(2, None, "H200 b", "discrete", (1, 4, 0))]
    assert [gpu_device_index(devices, g) for g in (0, 1, 2)] == [1, 2, None]


def test_items_are_read_when_a_slot_frees():
    backend, seen = Scripted(1, {}), []

    def items():
        for k in "abc":
            seen.append((k, [h[0] for h in backend.started]))  # what had started when k was made
            yield k, k

    assert [o.key for o in Executor(backend).run(str, items())] == ["a", "b", "c"]
    assert seen == [("a", []), ("b", ["a"]), ("c", ["a", "b"])]


def _pid_or_die(arg):
    if arg == "die":
        os._exit(5)
    return os.getpid()


def test_process_backend_k_tasks_per_worker_then_a_fresh_one():
    """One worker, 3 tasks each: tasks 0-2 share a process, 3-5 the next; neither is the caller."""
    backend = ProcessBackend(1, tasks_per_worker=3)
    with Executor(backend) as executor:
        pids = [o.value for o in executor.run(_pid, [(i, i) for i in range(6)])]
    assert pids[0] == pids[1] == pids[2] != pids[3] == pids[4] == pids[5] and os.getpid() not in pids
    assert backend.timing_lock is None  # one worker: nothing to share the GPU with


def test_a_worker_that_dies_loses_only_its_task_and_the_lock_goes():
    backend = ProcessBackend(2, tasks_per_worker=4)
    lock = backend.timing_lock
    assert lock and os.path.isfile(lock)  # two workers time their frames under it
    with Executor(backend, retries=0) as executor:
        got = {o.key: o for o in executor.run(_pid_or_die, [("a", "a"), ("die", "die"), ("b", "b"), ("c", "c")])}
    assert got["die"].error == "attempt 1: worker process exited with code 5 without a result"
    assert all(got[k].ok for k in "abc") and os.getpid() not in {got[k].value for k in "abc"}
    assert not os.path.exists(lock) and backend.timing_lock is None


def test_bad_tasks_per_worker():
    import pytest

    with pytest.raises(ValueError, match="tasks per worker must be at least 1"):
        ProcessBackend(2, tasks_per_worker=0)


def _time_under_lock(path):
    import time

    from rgraph.sweep.remote import timed_alone

    with timed_alone(path):
        return time.time()


def test_workers_wait_for_the_timing_lock(tmp_path):
    """While one holder has the lock, no worker enters its timed section."""
    import fcntl
    import threading
    import time

    backend = ProcessBackend(2)
    released: list[float] = []
    with open(backend.timing_lock, "a") as held:
        fcntl.flock(held, fcntl.LOCK_EX)

        def release():
            time.sleep(1.5)
            released.append(time.time())
            fcntl.flock(held, fcntl.LOCK_UN)

        thread = threading.Thread(target=release)
        thread.start()
        with Executor(backend) as executor:
            entered = [o.value for o in executor.run(_time_under_lock, [(i, backend.timing_lock) for i in range(2)])]
        thread.join()
    assert len(entered) == 2 and min(entered) >= released[0]
