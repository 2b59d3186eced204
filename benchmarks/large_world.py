"""Large-world transforms: what precision costs in time (issue 6 item 4).

    PYTHONPATH=. python3 benchmarks/large_world.py [--width 1920 --height 1080] [--frames 50]
        [--gpu-instances 20000 --gpu-triangles 512] [--distances 1e4,1e6,1e8,1e10,1e12]
        [--cpu-repeats 200] [--no-gpu] [--validate] [--json PATH]

One table, one row per camera distance from the origin (1e4 .. 1e12 m):

- error px: the largest vertex error in pixels against a float64 camera-relative reference
  (``rgraph.scene.large_world``; a small scene 0.2 .. 3 m from the camera) of three ways to
  transform: naive float32 world-space matrices; camera-relative float32 (what rgraph does:
  the translation ``position - camera`` formed in float64 on the CPU, then float32 on the
  GPU); world-space float64 (what a float64 vertex shader computes: IEEE-754 double products
  and sums, here evaluated in NumPy float64 -- the GPU rounds the same operations the same
  way up to fused multiply-adds, a few ulps at 1e12 m, i.e. ~1e-4 m there).
- CPU us/frame: the per-frame CPU work to give the GPU the transforms of every draw of the
  ``cct`` scene and of a 10,000-instance scene: camera-relative ``packing.draws_bytes`` as
  shipped (float64 model and normal matrices per draw, Python loop; must rerun whenever the
  camera moves), the same translation subtraction vectorized over stacked float64 matrices
  (the least camera-relative can cost), and naive float32 (world matrices cached once: the
  per-frame work is copying the cached bytes). Independent of the distance (measured at each).
- GPU ms: median GPU time (timestamps, ``execute_plan(...).timings``) of a raster pass drawing
  ``--gpu-instances`` procedural spheres of ``--gpu-triangles`` triangles
  (``benchmarks/large_world_gpu``), every vertex transformed camera-relative in float32 or
  world-space in float64 (``shaderFloat64``; "n/a" where the device lacks it).

``--json PATH`` writes the rows, the device, the settings and the command line.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from rgraph.impl import PassImpl, register  # noqa: E402
from rgraph.scene.camera import perspective, view_rotation  # noqa: E402
from rgraph.scene.large_world import DISTANCES, study  # noqa: E402

GPU_DIR = Path(__file__).resolve().parent / "large_world_gpu"
GPU_GRAPH = GPU_DIR / "graph.yaml"
CCT = ROOT / "graphs" / "scenes" / "cct.yaml"
DIRECTION = np.array([0.6, 0.48, 0.64]) / np.linalg.norm([0.6, 0.48, 0.64])
FORWARD = np.array([-0.3, -0.1, -1.0])
FOV_Y, NEAR = 45.0, 0.01
CLUSTER = 0.8  # metres: the spheres fill a cube this wide, 1.5 m in front of the camera


# ----------------------------------------------------------------------------- GPU pass


def transform_uniform(distance: float, aspect: float, instances: int, triangles: int) -> bytes:
    """The std140 ``Transform`` block of ``transform.vert`` (256 bytes) for a camera
    ``distance`` m from the origin and a cube of spheres ~1.5 m in front of it."""
    side = max(1, round(instances ** (1 / 3)))
    spacing = CLUSTER / side
    camera = DIRECTION * distance
    view_rot = view_rotation(FORWARD)
    proj = perspective(FOV_Y, aspect, NEAR)
    fwd = FORWARD / np.linalg.norm(FORWARD)
    rel_origin = fwd * 1.5 - np.full(3, (side - 1) * spacing / 2)  # the cube centred on the view axis
    origin = camera + rel_origin  # float64 world position of the cluster
    view_world = view_rot.copy()
    view_world[:3, 3] = -view_rot[:3, :3] @ camera
    out = bytearray(256)
    out[0:128] = (proj @ view_world).T.astype(np.float64).tobytes()  # column-major dmat4
    out[128:160] = np.array([*origin, 1.0], np.float64).tobytes()
    out[160:224] = (proj @ view_rot).T.astype(np.float32).tobytes()
    out[224:240] = np.array([*(origin - camera), 1.0], np.float32).tobytes()  # formed in float64
    out[240:256] = np.array([triangles, side, spacing, 0.35 * spacing], np.float32).tobytes()
    return bytes(out)


@register("large_world_transform")
class LargeWorldTransform(PassImpl):
    """Draws ``lw.instances`` x ``lw.triangles`` procedural triangles; ``lw.mode`` 0 transforms
    camera-relative in float32, 1 world-space in float64."""

    clear_values = {"color": (0.0, 0.0, 0.0, 1.0)}

    def __init__(self, setup):
        super().__init__(setup)
        self.mode = int(setup.param("lw.mode", 0))
        self.instances = int(setup.param("lw.instances", 2000))
        self.triangles = max(32, int(setup.param("lw.triangles", 512)) // 32 * 32)
        w, h = setup.extent
        data = transform_uniform(float(setup.param("lw.distance", 1e6)), w / h, self.instances, self.triangles)
        self.uniform = setup.host_buffer(len(data))
        self.uniform.write(data)
        from rgraph.vk.passkit import Binding

        self.sets = setup.descriptors([Binding(0, "uniform_buffer", buffers=((self.uniform.handle, len(data)),))])
        self.pipeline = setup.graphics_pipeline(str(GPU_DIR / "transform.vert"), str(GPU_DIR / "shade.frag"),
                                                [self.sets.layout], defines={"MODE": self.mode}, cull="NONE")

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3 * self.triangles, self.instances)


def enable_float64() -> None:
    """Ask the runtime's device creation to enable ``shaderFloat64`` where present (the
    runtime enables a fixed list of optional core features; float64 is not in it yet)."""
    from rgraph.vk import device

    if "shaderFloat64" not in device.OPTIONAL_CORE:
        device.OPTIONAL_CORE = (*device.OPTIONAL_CORE, "shaderFloat64")


def has_float64(device_index: int | None = None) -> tuple[bool, str]:
    from rgraph.vk.device import _query_features, create_device
    from rgraph.vk.instance import create_instance

    instance = create_instance(validate=False)
    try:
        dev = create_device(instance, device_index, verbose=False)
        try:
            core = _query_features(dev.physical.handle)[3]
            return bool(core.shaderFloat64), dev.physical.name
        finally:
            dev.destroy()
    finally:
        instance.destroy()


def gpu_run(mode: int, distance: float, *, size: tuple[int, int], frames: int, instances: int, triangles: int,
            validate: bool = False, device_index: int | None = None) -> dict[str, Any]:
    """Median GPU ms of the transform pass, the image, and validation messages (one device
    compiles and runs)."""
    import rgraph
    from rgraph.compiler.pipeline import compile_graph

    with rgraph.open_device(validate=validate, device=device_index, verbose=False) as gpu:
        plan = compile_graph(GPU_GRAPH, size=size, memory=gpu.memory_requirements(),
                             params={"lw.mode": str(mode), "lw.distance": repr(float(distance)),
                                     "lw.instances": str(instances), "lw.triangles": str(triangles)})
        result = gpu.load(plan).run_and_check(frames, check_data=False, read_outputs=True)
        result.messages = gpu.close()
    ms = (result.timings or {}).get("passes", {}).get("transform")
    return {"ms": ms, "image": result.outputs.get("color"), "messages": [str(m) for m in result.messages],
            "device": result.device_name}


# ----------------------------------------------------------------------------- CPU


def instanced_scene(extent: tuple[int, int], instances: int = 10_000):
    """The cct scene with its cartilage rim repeated ``instances`` times (a square grid)."""
    from rgraph.scene.build import build_scene
    from rgraph.spec.scene import Instances, load_scene

    scene = load_scene(CCT)
    side = round(instances ** 0.5)
    meshes = list(scene.model.meshes)
    meshes[1] = meshes[1].model_copy(update={"instances": Instances(grid=[side, 1, instances // side], spacing=0.03)})
    return build_scene(scene.model.model_copy(update={"meshes": meshes}), extent, "cct_10k")


def _median_us(fn, repeats: int) -> float:
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times) * 1e6)


def world_draws(scene, shift: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4, 4) float64 world model matrices of every draw (the scene moved by ``shift``) and
    (N, 4, 4) float32 normal matrices (rotation only: the same in every frame and space)."""
    draws = scene.draw_models(np.zeros(3))  # relative to the origin = world space
    world = np.stack([m for m, *_ in draws]).astype(np.float64)
    world[:, :3, 3] += shift
    return world, np.stack([n for _, n, *_ in draws]).astype(np.float32)


def pack_models(models: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(N, 32) float32: column-major model then normal matrix (the first 32 floats of a Draw)."""
    n = len(models)
    return np.concatenate([models.astype(np.float32).transpose(0, 2, 1).reshape(n, 16),
                           normals.transpose(0, 2, 1).reshape(n, 16)], axis=1)


def relative_models(world: np.ndarray, camera: np.ndarray) -> np.ndarray:
    """Camera-relative model matrices: the translation minus the camera, in float64."""
    rel = world.copy()
    rel[:, :3, 3] -= camera
    return rel


def cpu_costs(scene, distance: float, repeats: int) -> dict[str, float]:
    """Per-frame CPU microseconds (median) of the three ways to feed the draw transforms."""
    from rgraph.scene import packing

    shift = DIRECTION * distance
    camera = scene.camera(0).position + shift
    world, normals = world_draws(scene, shift)
    draws = world
    cached_naive = pack_models(world, normals).tobytes()

    def vectorized_relative() -> bytes:
        return pack_models(relative_models(world, camera), normals).tobytes()

    reps = max(3, repeats // max(1, len(draws) // 100))
    return {"draws": len(draws),
            "relative_shipped_us": _median_us(lambda: packing.draws_bytes(scene, 0), reps),
            "relative_vectorized_us": _median_us(vectorized_relative, repeats),
            "naive_cached_us": _median_us(lambda: bytearray(cached_naive), repeats)}


# ----------------------------------------------------------------------------- table


def fmt_px(v: float) -> str:
    return "inf" if not np.isfinite(v) else f"{v:.3g}"


def format_rows(rows: list[dict[str, Any]]) -> str:
    head = (f"{'distance m':>10} | {'err px: naive f32':>17} {'rel f32':>9} {'f64':>9} | "
            f"{'CPU us/frame cct (draws): rel / rel vec / naive':>48} | "
            f"{'CPU us/frame 10k: rel / rel vec / naive':>40} | {'GPU ms: rel f32':>15} {'f64':>8}")
    lines = [head, "-" * len(head)]
    for r in rows:
        c, k = r["cpu"]["cct"], r["cpu"]["10k"]
        gpu32 = "-" if r["gpu_ms_relative_f32"] is None else f"{r['gpu_ms_relative_f32']:.4g}"
        gpu64 = "n/a" if r["gpu_ms_f64"] is None else f"{r['gpu_ms_f64']:.4g}"
        lines.append(
            f"{r['distance']:>10.0e} | {fmt_px(r['err_px_naive_f32']):>17} {fmt_px(r['err_px_relative_f32']):>9} "
            f"{fmt_px(r['err_px_f64']):>9} | "
            f"{c['relative_shipped_us']:>10.1f} / {c['relative_vectorized_us']:>8.1f} / "
            f"{c['naive_cached_us']:>6.2f} ({c['draws']:>5}) | "
            f"{k['relative_shipped_us']:>12.0f} / {k['relative_vectorized_us']:>8.1f} / {k['naive_cached_us']:>7.2f} | "
            f"{gpu32:>15} {gpu64:>8}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=int, default=1920)
    parser.add_argument("--height", type=int, default=1080)
    parser.add_argument("--distances", default=",".join(f"{d:.0e}" for d in DISTANCES))
    parser.add_argument("--frames", type=int, default=50, help="GPU frames per run (median)")
    parser.add_argument("--gpu-instances", type=int, default=20000)
    parser.add_argument("--gpu-triangles", type=int, default=512, help="per instance, a multiple of 32")
    parser.add_argument("--gpu-size", default=None, help="WxH of the GPU test pass (default: --width x --height)")
    parser.add_argument("--cpu-repeats", type=int, default=200)
    parser.add_argument("--no-gpu", dest="gpu", action="store_false")
    parser.add_argument("--validate", action="store_true", help="GPU runs under validation (times not representative)")
    parser.add_argument("--device", type=int, default=None)
    parser.add_argument("--json", type=Path, default=None, help="write the rows as JSON")
    args = parser.parse_args(argv)
    command = "PYTHONPATH=. python3 benchmarks/large_world.py " + shlex.join(sys.argv[1:] if argv is None else argv)
    distances = [float(d) for d in args.distances.split(",")]
    gpu_size = (args.width, args.height)
    if args.gpu_size:
        w, _, h = args.gpu_size.lower().partition("x")
        gpu_size = (int(w), int(h))

    from rgraph.scene.build import load_scene_data

    scenes = {"cct": load_scene_data(CCT, (args.width, args.height)),
              "10k": instanced_scene((args.width, args.height))}
    errors = {r.distance: r for r in study(distances, width=args.width, height=args.height, fov_y=FOV_Y)}
    device, float64, messages = "-", False, []
    if args.gpu:
        enable_float64()
        float64, device = has_float64(args.device)
    rows = []
    for d in distances:
        e = errors[d]
        row: dict[str, Any] = {"distance": d, "err_px_naive_f32": e.naive_px, "err_px_relative_f32": e.relative_px,
                               "err_px_f64": e.naive64_px,
                               "cpu": {name: cpu_costs(s, d, args.cpu_repeats) for name, s in scenes.items()},
                               "gpu_ms_relative_f32": None, "gpu_ms_f64": None}
        if args.gpu:
            kw = dict(size=gpu_size, frames=args.frames, instances=args.gpu_instances, triangles=args.gpu_triangles,
                      validate=args.validate, device_index=args.device)
            rel = gpu_run(0, d, **kw)
            row["gpu_ms_relative_f32"] = rel["ms"]
            messages += rel["messages"]
            if float64:
                f64 = gpu_run(1, d, **kw)
                row["gpu_ms_f64"] = f64["ms"]
                messages += f64["messages"]
                both = np.abs(np.asarray(rel["image"], np.float64) - np.asarray(f64["image"], np.float64)).max(axis=-1)
                row["gpu_images_differ_fraction"] = float(np.mean(both > 0.02))
        rows.append(row)
    print(f"device: {device}; errors at {args.width}x{args.height}, fov_y {FOV_Y} deg; GPU pass at "
          f"{gpu_size[0]}x{gpu_size[1]}: {args.gpu_instances} spheres x {args.gpu_triangles} triangles "
          f"({3 * args.gpu_instances * args.gpu_triangles} vertices), median of {args.frames} frames"
          + ("" if not args.gpu or float64 else "; no shaderFloat64 on this device"))
    print(format_rows(rows))
    if args.validate:
        print(f"{len(messages)} validation message(s)")
        for m in messages:
            print(m)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"command": command, "device": device, "float64": float64,
                                         "size": [args.width, args.height], "gpu_size": list(gpu_size),
                                         "gpu_instances": args.gpu_instances, "gpu_triangles": args.gpu_triangles,
                                         "frames": args.frames, "rows": rows}, indent=1, default=float) + "\n")
    return 1 if args.validate and messages else 0


if __name__ == "__main__":
    sys.exit(main())
