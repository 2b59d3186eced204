"""The render thread's host cost of deformable meshes in ray tracing plans (rgraph/vk/rt_deform.py).

    python3 benchmarks/rt_deform_cost.py --scene graphs/scenes/cct.yaml

Per deformable mesh: the minimum CPU time (process time, over ``--repeats``) of
``write_positions`` (what each frame writes; the normals are the GPU's: rgraph/vk/rt_normals.py)
and of ``Deformer.traced`` (positions + the float64 NumPy normals: the reference, which an
earlier version wrote every frame). Then ``rt_standalone`` on the
scene for ``--frames`` frames (``--size``, default 48x32): the frame loop's median host update
(``render_thread.update_us``: scene, accel and pass updates) and CPU time per frame; with
``--static`` also the same scene with ``deformable`` removed, for the difference.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path.cwd()))  # the checkout it is run from, not an installed rgraph

from rgraph.resources import builtin_passes  # noqa: E402
from rgraph.scene.build import load_scene_data  # noqa: E402


def min_cpu_ms(fn, repeats: int) -> float:
    best = float("inf")
    for i in range(repeats):
        t0 = time.process_time()
        fn(i)
        best = min(best, time.process_time() - t0)
    return best * 1e3


def run(graph: str, scene: str, size: tuple[int, int], frames: int) -> dict:
    from rgraph.api import compile_for_device
    from rgraph.vk.executor import execute_plan

    # sized for the device it runs on (accel scratch sizes differ between drivers)
    result = execute_plan(compile_for_device(graph, scene_path=scene, size=size), frames=frames)
    return result.timings["render_thread"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="graphs/scenes/cct.yaml")
    ap.add_argument("--graph", default="rt_standalone")
    ap.add_argument("--size", type=int, nargs=2, default=(48, 32))
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--repeats", type=int, default=50)
    ap.add_argument("--static", action="store_true", help="also run the scene without deformable meshes")
    args = ap.parse_args()
    builtin_passes()
    data = load_scene_data(args.scene, tuple(args.size))
    for mesh in data.deformable:
        d = mesh.deformer
        out = np.empty((mesh.data.vertex_count, 3), dtype=np.float32)
        traced = min_cpu_ms(lambda i, d=d: d.traced(i / 60.0), args.repeats)
        written = min_cpu_ms(lambda i, d=d, out=out: d.write_positions(i / 60.0, out), args.repeats)
        print(f"mesh {mesh.data.vertex_count} vertices, {mesh.data.triangle_count} triangles: write_positions "
              f"{written:.3f} ms, traced (CPU reference normals) {traced:.3f} ms (min CPU of {args.repeats})")
    scenes = [("deformable", args.scene)]
    if args.static:
        text = Path(args.scene).read_text().replace("deformable: true", "deformable: false")
        fd, path = tempfile.mkstemp(suffix=".yaml", dir=Path(args.scene).parent)
        os.close(fd)
        Path(path).write_text(text)
        scenes.append(("static", path))
    try:
        for label, scene in scenes:
            r = run(args.graph, scene, tuple(args.size), args.frames)
            print(f"{args.graph} {label} {args.size[0]}x{args.size[1]} {args.frames} frames: update median "
                  f"{r['update_us']:.0f} us, render thread CPU {r['cpu_us_per_frame']:.0f} us/frame")
    finally:
        if args.static:
            os.unlink(scenes[1][1])
    print(f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
