"""The logic tick of the skinned-characters test: NumPy animation of C characters x B bones.

Per tick (median over ``--ticks`` after ``--warmup`` ticks): the local pose (one sine per bone
per character), forward kinematics (one vectorised step per depth level of the skeleton),
half-float packing of the joint transforms - the state the renderer interpolates (the vertex
shader applies the inverse binds) - and, with ``--write``, its copy into mapped memory's
stand-in (a bytearray). Wall time (perf_counter) and the thread's CPU time (thread_time: less
sensitive to other processes on a shared machine).
Float32 (the logic path). Target: well under 16.7 ms (one 60 Hz tick) for 1,024 x 256.

    python -m benchmarks.skin_anim [--characters 1024] [--bones 256] [--ticks 60] [--warmup 5] [--write]
        [--threads 1,2,4,8]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from rgraph.scene.animation import LOGIC_HZ, Animator
from rgraph.scene.character import build_rig
from rgraph.scene.skinning import forward_kinematics, pack_bones

STAGES = ("local", "fk", "pack", "write", "total")


def measure(characters: int, bones: int, ticks: int, warmup: int, write: bool,
            clock=time.perf_counter) -> dict[str, float]:
    """Median milliseconds per stage of one logic tick by ``clock``."""
    rig = build_rig(bones)
    anim = Animator(rig, characters, seed=1)
    sink = bytearray(characters * bones * 16)
    times: dict[str, list[float]] = {s: [] for s in STAGES}
    for tick in range(warmup + ticks):
        t0 = clock()
        local = anim.local_pose(tick / LOGIC_HZ)
        t1 = clock()
        world = forward_kinematics(rig.skeleton, local)
        t2 = clock()
        packed = pack_bones(world)
        t3 = clock()
        if write:
            sink[:] = memoryview(np.ascontiguousarray(packed)).cast("B")
        t4 = clock()
        if tick >= warmup:
            for name, dt in zip(STAGES, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t4 - t0), strict=True):
                times[name].append(1e3 * dt)
    return {s: statistics.median(v) for s, v in times.items()}


def threaded(characters: int, bones: int, ticks: int, warmup: int, threads: int) -> float:
    """Median ms of ``Animator.state`` (all stages) with ``threads`` chunks of characters."""
    anim = Animator(build_rig(bones), characters, seed=1)
    got = []
    for tick in range(warmup + ticks):
        t0 = time.perf_counter()
        anim.state(tick, threads=threads)
        if tick >= warmup:
            got.append(1e3 * (time.perf_counter() - t0))
    return statistics.median(got)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--characters", type=int, default=1024)
    ap.add_argument("--bones", type=int, default=256)
    ap.add_argument("--ticks", type=int, default=60)
    ap.add_argument("--warmup", type=int, default=5)
    ap.add_argument("--write", action="store_true", help="also copy the packed state (4 MiB at 1024 x 256)")
    ap.add_argument("--threads", default="1,2,4,8", help="Animator.state with these thread counts (comma list)")
    a = ap.parse_args(argv)
    rig = build_rig(a.bones)
    ms = measure(a.characters, a.bones, a.ticks, a.warmup, a.write)
    cpu = measure(a.characters, a.bones, a.ticks, a.warmup, a.write, time.thread_time)
    print(f"skin_anim: {a.characters} characters x {a.bones} bones (skeleton depth {rig.skeleton.depth}, "
          f"{rig.mesh.triangle_count} triangles), {a.characters * a.bones * 16 / 2**20:.1f} MiB per state, "
          f"numpy {np.__version__}")
    print("median wall ms per tick: " + ", ".join(f"{s} {ms[s]:.2f}" for s in STAGES))
    print("median CPU ms per tick:  " + ", ".join(f"{s} {cpu[s]:.2f}" for s in STAGES))
    budget = 1e3 / LOGIC_HZ
    print(f"tick budget at {LOGIC_HZ:.0f} Hz: {budget:.2f} ms; used {100 * ms['total'] / budget:.0f}%")
    for n in (int(x) for x in a.threads.split(",") if x):
        t = threaded(a.characters, a.bones, a.ticks, a.warmup, n)
        print(f"Animator.state, {n} thread(s): {t:.2f} ms per tick ({100 * t / budget:.0f}% of the budget)")


if __name__ == "__main__":
    main()
