"""The logic tick of the skinned-characters test: NumPy animation of C characters x B bones.

Three parts, medians over ``--ticks`` after ``--warmup`` ticks, wall (perf_counter) and CPU
(thread_time: less sensitive to other processes on a shared machine):

- ``reference``: the readable path (``Animator.reference_state``: ``pack_bones(pose)``) stage
  by stage - the local pose (one sine per bone per character), forward kinematics (one
  vectorised step per depth level), half-float packing - in float32 and, total only, float64:
  where a tick's time goes without the kernel;
- ``back to back``: a reference tick and a kernel tick in turn, minimum and median CPU;
- ``kernel``: ``Animator.state`` (rgraph.scene.skin_kernel: a tape of NumPy calls on
  preallocated buffers, bit-identical - checked on every timed tick), with ``--threads``;
- ``--worker``: a ``SkinWorker`` process (rgraph.scene.skin_worker) paced at ``--hz`` as the
  logic thread does: the worker's evaluation time, and the caller's per tick - its wait in
  ``fetch`` (wall) and its CPU time for fetch plus the copy of the state into a stand-in of
  mapped memory (a bytearray): what the logic thread holds the GIL for;
- ``--contention``: a stand-in render thread (``--frames`` frames paced at 120 Hz, each 40
  GIL-releasing C calls through ctypes - as the frame loop's Vulkan calls through cffi - and a
  little Python between them) timed while a logic thread ticks at ``--hz``: with no logic,
  with the skinning on the logic thread (``skin.worker=thread``) and in the worker process
  (``skin.worker=process``): the frame's mean, median and p90 microseconds.

Target: well under 16.7 ms (one 60 Hz tick) for 1,024 x 256.

    python -m benchmarks.skin_anim [--characters 1024] [--bones 256] [--ticks 60] [--warmup 5]
        [--threads 1,2,4] [--worker] [--hz 60] [--contention] [--frames 600]
"""

from __future__ import annotations

import argparse
import ctypes
import statistics
import threading
import time

import numpy as np

from rgraph.scene.animation import LOGIC_HZ, Animator
from rgraph.scene.character import build_rig
from rgraph.scene.skinning import forward_kinematics, pack_bones

STAGES = ("local", "fk", "pack", "total")


def reference(anim: Animator, ticks: int, warmup: int, clock=time.perf_counter) -> dict[str, float]:
    """Median milliseconds per stage of the reference path by ``clock``."""
    times: dict[str, list[float]] = {s: [] for s in STAGES}
    for tick in range(warmup + ticks):
        t0 = clock()
        local = anim.local_pose(tick / LOGIC_HZ)
        t1 = clock()
        world = forward_kinematics(anim.rig.skeleton, local)
        t2 = clock()
        pack_bones(world)
        t3 = clock()
        if tick >= warmup:
            for name, dt in zip(STAGES, (t1 - t0, t2 - t1, t3 - t2, t3 - t0), strict=True):
                times[name].append(1e3 * dt)
    return {s: statistics.median(v) for s, v in times.items()}


def back_to_back(anim: Animator, ticks: int, warmup: int) -> dict[str, tuple[float, float]]:
    """(minimum, median) CPU ms of the reference and of the kernel, one tick of each in turn
    (A/B/A/B: a shared machine's drift hits both alike)."""
    out = np.empty((anim.bones, anim.characters, 8), np.float16)
    got: dict[str, list[float]] = {"reference": [], "kernel": []}
    for tick in range(warmup + ticks):
        c0 = time.thread_time()
        anim.reference_state(tick)
        c1 = time.thread_time()
        anim.state(tick, out=out)
        c2 = time.thread_time()
        if tick >= warmup:
            got["reference"].append(1e3 * (c1 - c0))
            got["kernel"].append(1e3 * (c2 - c1))
    return {k: (min(v), statistics.median(v)) for k, v in got.items()}


def kernel(anim: Animator, ticks: int, warmup: int, threads: int) -> tuple[float, float, bool]:
    """(median wall ms, median CPU ms of the calling thread, bit-identical on every timed
    tick) of ``Animator.state`` with ``threads`` chunks of characters."""
    out = np.empty((anim.bones, anim.characters, 8), np.float16)
    wall, cpu, same = [], [], True
    for tick in range(warmup + ticks):
        t0, c0 = time.perf_counter(), time.thread_time()
        anim.state(tick, threads=threads, out=out)
        t1, c1 = time.perf_counter(), time.thread_time()
        if tick >= warmup:
            wall.append(1e3 * (t1 - t0))
            cpu.append(1e3 * (c1 - c0))
            same = same and np.array_equal(out.view(np.uint16), anim.reference_state(tick).view(np.uint16))
    return statistics.median(wall), statistics.median(cpu), same


def worker(anim: Animator, ticks: int, warmup: int, threads: int, hz: float) -> dict[str, float]:
    """A SkinWorker paced at ``hz``: the worker's evaluation (wall, CPU ms), the caller's wait
    in fetch (ms) and its CPU (us) for fetch + copy, medians; the start-up (s)."""
    from rgraph.scene.skin_worker import SkinWorker

    sink = np.empty(anim.bones * anim.characters * 16, np.uint8)
    t0 = time.perf_counter()
    with SkinWorker([anim], hz, threads) as w:
        started = time.perf_counter() - t0
        caller_cpu = []
        due = time.perf_counter()
        for tick in range(warmup + ticks):
            c0 = time.thread_time()
            np.copyto(sink, w.fetch(tick))
            if tick >= warmup:
                caller_cpu.append(1e6 * (time.thread_time() - c0))
            due += 1.0 / hz
            time.sleep(max(0.0, due - time.perf_counter()))
        same = np.array_equal(sink, anim.reference_state(warmup + ticks - 1).view(np.uint8).reshape(-1))
        n = ticks
        return {"start_s": started, "tick_ms": 1e3 * statistics.median(w.compute_s[-n:]),
                "tick_cpu_ms": 1e3 * statistics.median(w.compute_cpu_s[-n:]),
                "wait_ms": 1e3 * statistics.median(w.wait_s[-n:]), "caller_cpu_us": statistics.median(caller_cpu),
                "identical": same}


def render_frames(frames: int, calls: int = 40, fps: float = 120.0) -> list[float]:
    """Microseconds of each stand-in render-thread frame (``calls`` GIL-releasing C calls)."""
    libc = ctypes.CDLL(None)
    getpid = libc.getpid  # ctypes releases the GIL around every foreign call
    got = []
    due = time.perf_counter()
    for _ in range(frames):
        t0 = time.perf_counter()
        acc = 0
        for k in range(calls):
            acc += getpid() + k
        got.append(1e6 * (time.perf_counter() - t0))
        due += 1.0 / fps
        time.sleep(max(0.0, due - time.perf_counter()))
    return got


def contention(anim: Animator, frames: int, hz: float, threads: int) -> dict[str, tuple[float, float, float]]:
    """(mean, median, p90) us of the stand-in render frames per logic mode."""
    from rgraph.scene.skin_worker import SkinWorker

    def percentiles(values: list[float]) -> tuple[float, float, float]:
        ordered = sorted(values)
        return statistics.fmean(values), statistics.median(values), ordered[int(0.9 * len(ordered))]

    out = {"no logic": percentiles(render_frames(frames))}
    sink = np.empty(anim.bones * anim.characters * 16, np.uint8)
    for mode in ("thread", "process"):
        worker = SkinWorker([anim], hz, threads) if mode == "process" else None
        stop = threading.Event()

        def logic(worker: SkinWorker | None = worker, stop: threading.Event = stop) -> None:
            tick, due = 0, time.perf_counter()
            while not stop.is_set():
                state = worker.fetch(tick) if worker is not None else anim.state(tick, hz, threads).view(np.uint8)
                np.copyto(sink, state.reshape(-1))
                tick += 1
                due += 1.0 / hz
                stop.wait(max(0.0, due - time.perf_counter()))

        thread = threading.Thread(target=logic, daemon=True)
        thread.start()
        try:
            time.sleep(0.2)
            out[f"skinning on the logic thread ({threads} thread(s))" if mode == "thread"
                else f"skinning in a worker process ({threads} thread(s))"] = percentiles(render_frames(frames))
        finally:
            stop.set()
            thread.join()
            if worker is not None:
                worker.close()
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--characters", type=int, default=1024)
    ap.add_argument("--bones", type=int, default=256)
    ap.add_argument("--ticks", type=int, default=60)
    ap.add_argument("--warmup", type=int, default=5)
    ap.add_argument("--threads", default="1,2,4", help="Animator.state with these thread counts (comma list)")
    ap.add_argument("--worker", action="store_true", help="also a SkinWorker process paced at --hz (each --threads)")
    ap.add_argument("--hz", type=float, default=LOGIC_HZ)
    ap.add_argument("--contention", action="store_true", help="a stand-in render thread beside the logic thread")
    ap.add_argument("--frames", type=int, default=600, help="--contention: stand-in render frames per mode")
    a = ap.parse_args(argv)
    rig = build_rig(a.bones)
    anim = Animator(rig, a.characters, seed=1)
    budget = 1e3 / a.hz
    print(f"skin_anim: {a.characters} characters x {a.bones} bones (skeleton depth {rig.skeleton.depth}, "
          f"{rig.mesh.triangle_count} triangles), {a.characters * a.bones * 16 / 2**20:.1f} MiB per state, "
          f"numpy {np.__version__}; tick budget at {a.hz:g} Hz: {budget:.2f} ms")
    ms = reference(anim, a.ticks, a.warmup)
    cpu = reference(anim, a.ticks, a.warmup, time.thread_time)
    exact = reference(Animator(rig, a.characters, seed=1, dtype=np.float64), max(a.ticks // 4, 3), 1,
                      time.thread_time)
    print("reference (pack_bones(pose)), median wall ms: " + ", ".join(f"{s} {ms[s]:.2f}" for s in STAGES))
    print("reference, median CPU ms:                     " + ", ".join(f"{s} {cpu[s]:.2f}" for s in STAGES))
    print(f"reference in float64, median CPU ms: total {exact['total']:.2f}")
    ab = back_to_back(anim, a.ticks, a.warmup)
    (rmin, rmed), (kmin, kmed) = ab["reference"], ab["kernel"]
    print(f"back to back, CPU ms min / median: reference {rmin:.2f} / {rmed:.2f}, kernel {kmin:.2f} / {kmed:.2f} "
          f"({rmin / kmin:.2f}x / {rmed / kmed:.2f}x)")
    threads = [int(x) for x in a.threads.split(",") if x]
    for n in threads:
        wall, c, same = kernel(anim, a.ticks, a.warmup, n)
        print(f"kernel (Animator.state), {n} thread(s): {wall:.2f} ms wall ({100 * wall / budget:.0f}% of the "
              f"budget), {c:.2f} ms CPU of the calling thread, {ms['total'] / wall:.2f}x faster than the "
              f"reference (wall); bit-identical: {'yes' if same else 'NO'}")
    if a.worker:
        mib = a.characters * a.bones * 16 / 2**20
        for n in threads:
            r = worker(anim, a.ticks, a.warmup, n, a.hz)
            print(f"worker process, {n} thread(s): started in {r['start_s']:.2f} s; per state {r['tick_ms']:.2f} ms "
                  f"wall, {r['tick_cpu_ms']:.2f} ms CPU (all its threads); the caller waits {r['wait_ms']:.3f} ms "
                  f"and spends {r['caller_cpu_us']:.0f} us CPU per tick (fetch + the {mib:.1f} MiB copy); "
                  f"bit-identical: {'yes' if r['identical'] else 'NO'}")
    if a.contention:
        for mode, (mean, median, p90) in contention(anim, a.frames, a.hz, threads[0]).items():
            print(f"stand-in render thread (40 C calls per frame), {mode}: mean {mean:.1f} us, median {median:.1f}, "
                  f"p90 {p90:.1f}")


if __name__ == "__main__":
    main()
