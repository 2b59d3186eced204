"""The frame loop: fence pacing, timestamp reads, per-frame host updates, prebuilt submits."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import Any

from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.runtime.commands import rerecord
from rgraph.vk.runtime.setup import FRAMES_IN_FLIGHT

#: Vulkan calls bracketed in ``run_frames`` marks before the submits, in order.
FRAME_CALLS = ("vkWaitForFences", "vkGetQueryPoolResults", "vkResetFences", "vkResetQueryPool")


def run_for(run: Callable[[int], Any], seconds: float, min_frames: int = 1, max_batch: int = 64) -> int:
    """Warm-up: call ``run(n)`` (``Executable.run``, ``MultiExecutable.run``, an executor's
    ``run_frames``) in batches of 1, 2, 4 ... ``max_batch`` frames until ``seconds`` of wall time
    have passed and at least ``min_frames`` frames ran. Returns the frames run."""
    done, batch, start = 0, 1, time.perf_counter()
    while done < min_frames or time.perf_counter() - start < seconds:
        run(batch)
        done += batch
        batch = min(2 * batch, max_batch)
    return done


def marks_per_frame(submit_calls: int) -> int:
    """Marks ``run_frames`` takes per frame: the start, then a pair per Vulkan call."""
    return 1 + 2 * (len(FRAME_CALLS) + submit_calls)


def run_frames(ex: Any, frames: int, marks: list[float] | None = None) -> dict[str, Any]:
    """Submit ``frames`` frames (continuing the executor's frame count); per-pass GPU medians
    from timestamps.

    ``marks`` (if given) gets time.perf_counter() readings, ``marks_per_frame(calls)`` per
    frame (calls in ``FRAME_CALLS`` order): the frame's start, then a (before, after) pair around each
    Vulkan call - the fence wait (time blocked on the GPU), the timestamp read, the fence
    reset, the query reset, each vkQueueSubmit2 - with the per-frame updates (scene and
    pass ``update`` hooks) and semaphore values between them. A call a frame skips (no
    timestamps yet) still gets its pair, an empty interval. benchmarks/frame_cpu.py splits
    a frame into blocked, Vulkan calls and Python from them.

    The loop calls the binding's raw cffi functions with prebuilt arrays: per frame one fence
    wait and reset, one query read into a preallocated buffer (copied out as bytes; with
    ``ex.timestamp_every`` = k > 1 only every k-th use of a frame set reads its timestamps, the
    per-pass medians then come from 1 / k of the frames), the timeline values, and one
    vkQueueSubmit2 per call of ``submit_calls``. The timestamp queries are reset by each pass
    in its command buffer (``rgraph.vk.runtime.commands``), from the host only where a pass
    runs on a transfer-only queue family.

    With a logic thread (``ex.logic``: ``rgraph run --logic-hz``) it runs while the frames do
    (started here, stopped when they end or fail); an error there stops the loop. The timings
    report the render thread's CPU time per frame (``render_thread``) and the logic's ticks.
    """
    import numpy as np

    v = vk()
    lib, ffi = v.lib, v.ffi
    dev = ex.device
    log = ex.log
    validate = ex.instance.validate
    n = len(ex.plan["passes"])
    handle = dev.handle
    fence_counts = [len(f) for f in ex.fences]
    fence_arrays = ex.fence_arrays
    pools = ex.query_pools
    timestamps = n > 0 and all(dev.timestamp_valid_bits.get(p["queue"], 0) > 0 for p in ex.plan["passes"])
    host_reset = timestamps and getattr(ex, "host_query_reset", True)
    every = max(1, int(getattr(ex, "timestamp_every", 1)))  # read one frame's timestamps in this many
    query_buffer = ffi.new("uint64_t[]", max(2 * n, 1))
    query_bytes = ffi.buffer(query_buffer)
    query_size = 16 * n
    read_rows: list[bytes] = []  # each read frame's timestamps (bytes: a copy in one C call)
    query_flags = v.VK_QUERY_RESULT_64_BIT
    cpu_s = [0.0] * frames  # plain lists: no NumPy call in the loop
    update_s = [0.0] * frames
    submitted = [False] * FRAMES_IN_FLIGHT
    scene, updaters = ex.scene_gpu, ex.updaters
    update = scene.frame_update() if scene is not None else None
    records = scene is not None and scene.records_per_frame
    prepare = scene.prepare if scene is not None and scene.deform is not None and ex.logic is None else None
    wait_fences, reset_fences, submit2 = lib.vkWaitForFences, lib.vkResetFences, lib.vkQueueSubmit2
    get_queries, reset_queries = lib.vkGetQueryPoolResults, lib.vkResetQueryPool
    # per set: (queue, infos count, infos, fence, context) of each vkQueueSubmit2; semaphore values
    calls_of = [[(c.queue, c.count, c.infos, c.fence, c.context) for c in ex.submit_calls[k]]
                for k in range(FRAMES_IN_FLIGHT)]
    slots_of = ex.value_slots
    timeout = dev.fence_timeout_ns
    poll, not_yet = fence_wait() == "poll", v.VK_TIMEOUT
    perf = time.perf_counter
    timed = marks is not None
    mark = marks.append if marks is not None else None
    base = ex.frames_done
    origin = getattr(ex, "frame_origin", 0)
    logic = ex.logic
    thread_t0 = time.thread_time()
    wall_t0 = perf()
    try:
        if logic is not None:
            try:
                logic.start()  # tick 0 runs here
            except Exception as exc:  # noqa: BLE001 -- the step's own error, reported as such
                raise ExecutionError(f"frame {base}: the logic thread failed: {exc!r}") from exc
        for local in range(frames):
            frame = base + local
            s = frame % FRAMES_IN_FLIGHT
            t0 = perf()
            if timed:
                mark(t0)
            log.context = f"frame {frame}"  # also a hook: tests/vk/test_soak.py samples RSS on it
            count = fence_counts[s]
            if timed:
                mark(perf())
            if count:
                if poll:  # diagnostic (RGRAPH_FENCE_WAIT=poll): the thread never sleeps in the wait
                    while (result := wait_fences(handle, count, fence_arrays[s], 1, 0)) == not_yet:
                        pass
                else:
                    result = wait_fences(handle, count, fence_arrays[s], 1, timeout)
                if result:
                    check_result(result, "vkWaitForFences")
            if timed:
                mark(perf())
                mark(perf())
            if count and submitted[s] and timestamps and (frame // FRAMES_IN_FLIGHT) % every == 0:
                read = get_queries(handle, pools[s], 0, 2 * n, query_size, query_buffer, 8, query_flags) == 0
                if timed:
                    mark(perf())
                if read:
                    read_rows.append(query_bytes[:])
            elif timed:
                mark(perf())
            if timed:
                mark(perf())
            if count:
                result = reset_fences(handle, count, fence_arrays[s])
                if result:
                    check_result(result, "vkResetFences")
            if timed:
                mark(perf())
                mark(perf())
            if count and host_reset:  # otherwise each pass resets its queries on the GPU
                reset_queries(handle, pools[s], 0, 2 * n)
            if timed:
                mark(perf())
            if logic is not None and logic.error is not None:
                raise ExecutionError(f"frame {frame}: the logic thread failed: {logic.error!r}")
            u0 = perf()
            content = frame - origin  # the frame's content index (camera, animation, probe values)
            if update is not None:
                update(content, s)
            for p in updaters:
                p.update(content, s)
            update_s[local] = perf() - u0
            if records:  # draw.mode=naive: this frame's draws of the CPU-visible objects
                rerecord(ex, s)
            for slot, offset in slots_of[s]:
                slot.value = frame + offset
            for queue, infos_count, infos, fence, context in calls_of[s]:
                if validate:
                    log.context = f"frame {frame} {context}"
                if timed:
                    mark(perf())
                result = submit2(queue, infos_count, infos, fence)
                if result:
                    check_result(result, "vkQueueSubmit2")
                if timed:
                    mark(perf())
            submitted[s] = True
            if prepare is not None:  # the next frame's host data, while the CPU is warm
                prepare(content + 1)
            cpu_s[local] = perf() - t0
    finally:
        if logic is not None:
            logic.stop()
    render = {"cpu_us_per_frame": (time.thread_time() - thread_t0) * 1e6 / frames if frames else None,
              "wall_us_per_frame": (perf() - wall_t0) * 1e6 / frames if frames else None,
              "update_us": float(np.median(update_s)) * 1e6 if frames else None}
    ex.frames_done = base + frames
    log.context = "finishing"
    for s in range(FRAMES_IN_FLIGHT):
        if submitted[s] and fence_counts[s]:
            check_result(wait_fences(handle, fence_counts[s], fence_arrays[s], 1, timeout), "vkWaitForFences")
            if timestamps and get_queries(handle, pools[s], 0, 2 * n, query_size, query_buffer, 8, query_flags) == 0:
                read_rows.append(query_bytes[:])
    rows = np.frombuffer(b"".join(read_rows), dtype=np.uint64).reshape(len(read_rows), 2 * n) if read_rows and n \
        else np.zeros((0, 2 * n), dtype=np.uint64)
    out = timings(ex, rows, frames, np.asarray(cpu_s))
    out["render_thread"] = render
    if logic is not None:
        out["logic"] = {**logic.stats(), "alpha_range": list(scene.alpha_range) if scene is not None else None,
                        "skin": scene.skin.logic_stats() if scene is not None and scene.skin.active else None}
    return out


def timings(ex: Any, rows: Any, frames: int, cpu_s: Any) -> dict[str, Any]:
    """Medians (ms) from timestamp rows (per frame: start, end of each pass)."""
    import numpy as np

    period = ex.device.timestamp_period_ns / 1e6
    per_pass: dict[str, float | None] = {p["name"]: None for p in ex.plan["passes"]}
    total = None
    if len(rows):
        stamps = rows.astype(np.float64)
        starts, ends = stamps[:, 0::2], stamps[:, 1::2]
        for i, p in enumerate(ex.plan["passes"]):
            per_pass[p["name"]] = float(np.median(ends[:, i] - starts[:, i])) * period
        total = float(np.median(ends.max(axis=1) - starts.min(axis=1))) * period
    from rgraph.vk.pass_intervals import pass_intervals

    return {"passes": per_pass, "total_ms": total, "frames": frames,
            "cpu_submit_ms": float(np.median(cpu_s)) * 1000.0 if frames else None,
            "intervals": pass_intervals(ex.plan, rows, period)}


def fence_wait() -> str:
    """How the frame loop waits for a frame set's fences: ``block`` (default: one
    vkWaitForFences that sleeps until they signal) or ``poll`` (``RGRAPH_FENCE_WAIT=poll``, a
    diagnostic: vkWaitForFences with timeout 0 until they signal, so the thread stays on its
    core with its caches warm; the wait then burns CPU, which ``render_thread.cpu_us_per_frame``
    shows, and the frame's work after the wait runs warm: on the H200, whether the render
    thread's time after a long wait is the cold wake-up's)."""
    way = os.environ.get("RGRAPH_FENCE_WAIT", "") or "block"
    if way not in ("block", "poll"):
        raise ExecutionError(f"RGRAPH_FENCE_WAIT must be block or poll, not {way!r}")
    return way


def check_result(result: int, call: str) -> None:
    if result != 0:
        raise ExecutionError(f"{call} failed: {names_of_result(result)}")


def names_of_result(result: int) -> str:
    v = vk()
    for name in dir(v):
        if name.startswith("VK_") and not name.startswith("VK_STRUCTURE") and getattr(v, name) == result and (
                name.startswith("VK_ERROR_") or name in ("VK_TIMEOUT", "VK_NOT_READY", "VK_INCOMPLETE")):
            return name
    return f"VkResult {result}"
