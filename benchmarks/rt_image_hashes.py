"""One line per run: graph, scene, frames and the sha256 of each output the ray tracing graphs
read back (lavapipe or any device with ray tracing).

    python3 benchmarks/rt_image_hashes.py > after.txt      # in each checkout, then diff

Equal lines mean byte-identical images: the check that a change to the ray tracing runtime
leaves scenes it does not target unchanged (docs/raytracing.md, deformable meshes).
``--scene`` adds scenes (default: the tiny ray tracing scene and two hard test scenes).
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

sys.path.insert(0, str(Path.cwd()))  # the checkout it is run from, not an installed rgraph

from rgraph.compiler.pipeline import compile_graph  # noqa: E402
from rgraph.resources import builtin_passes  # noqa: E402
from rgraph.vk.executor import execute_plan  # noqa: E402

GRAPHS = ("rt_standalone", "rt_hybrid", "rt_hybrid_raster")
SCENES = ("graphs/scenes/rt_tiny.yaml", "tests/data/rt/vis_hard.yaml", "tests/data/rt/wave_tir.yaml")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", action="append", default=[], help="more scene files")
    ap.add_argument("--size", type=int, nargs=2, default=(48, 32))
    ap.add_argument("--frames", type=int, default=3)
    args = ap.parse_args()
    builtin_passes()
    for scene in (*SCENES, *args.scene):
        for graph in GRAPHS:
            plan = compile_graph(graph, scene_path=scene, size=tuple(args.size))
            result = execute_plan(plan, frames=args.frames, read_outputs=True)
            digests = " ".join(f"{name}={hashlib.sha256(value.tobytes()).hexdigest()[:16]}"
                               for name, value in sorted(result.outputs.items()))
            print(f"{graph} {scene} {args.frames} {digests} messages={len(result.messages)}", flush=True)


if __name__ == "__main__":
    main()
