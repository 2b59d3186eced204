"""Large-world precision: camera-relative float64 -> float32 vs naive world-space transforms.

    .venv/bin/python benchmarks/large_world.py [--width 1920 --height 1080]

Prints, for a camera 1e4 .. 1e12 m from the origin with a small scene around it (vertices
0.2 .. 3 m away), the largest vertex error in pixels against a float64 reference.
"""

from __future__ import annotations

import argparse

from rgraph.scene.large_world import DISTANCES, format_table, study


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=int, default=1920)
    parser.add_argument("--height", type=int, default=1080)
    parser.add_argument("--fov", type=float, default=45.0)
    args = parser.parse_args()
    rows = study(DISTANCES, width=args.width, height=args.height, fov_y=args.fov)
    print(f"vertex error in pixels at {args.width}x{args.height}, fov_y {args.fov} deg "
          f"({rows[0].vertices} vertices, 0.2 .. 3 m from the camera)")
    print(format_table(rows))


if __name__ == "__main__":
    main()
