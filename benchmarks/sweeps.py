"""What accuracy costs in time (issue 6 item 1, issue 21): the committed sweeps, one knob at a
time, each group against a reference setting more accurate than any shipping setting.

    PYTHONPATH=. python3 benchmarks/sweeps.py [--size 1920x1080] [--frames 100]
        [--groups hbao,sss,bloom,shadow,ibl,rt,clusters] [--workers N] [--validate] -o DIR

Writes every group's ``rgraph sweep`` outputs into ``DIR/<group>`` (sweep.csv, sweep.md,
Pareto plots, images, error maps), then ``DIR/accuracy-vs-time.md``: the device, the exact
command line, and per group its reference, a table (the group's own passes' GPU ms, the
frame's, and the errors) and links to its plots. HDR metrics are on the image the group's
passes produce (``--hdr``): the AO image for HBAO, the diffuse image after SSS for SSS, the
HDR image for the others (none for ``rt`` and ``clusters``, as in session 7).

Without ``--workers`` the groups run one after the other in this process (the NVIDIA driver
refuses instances after ~40 in one process: there, run one group per process). With
``--workers N`` every setting of every group renders in its own worker process through ONE
pool of N (:func:`rgraph.sweep.pool.run_groups`): all references first, then the groups'
settings in turn, so the pool never waits on one group's reference; each group's outputs are
written the moment its last rendering lands, and equal its one-process sweep's except
measured times (:mod:`rgraph.sweep.same`).

Groups (knobs, reference, params under every setting):

- ``hbao``: ``hbao.directions`` 2,4,8,16, ``hbao.steps`` 2,4,8, ``hbao.scale`` 0.25,0.5;
  reference ``hbao.scale=1 hbao.directions=32 hbao.steps=32`` (full resolution).
- ``sss``: ``sss.samples`` 11,17,25 (separable); reference ``sss.kernel=2d sss.samples=25``
  (the non-separable 2D convolution of the same profile).
- ``bloom``: ``bloom.radius`` 8,12,16,24 (truncation, full-res px; sigma fixed at the
  graph's 8 px), ``bloom.scale`` 0.25,0.5; reference ``bloom.scale=1 bloom.radius=24``
  (full-resolution Gaussian truncated at 3 sigma).
- ``shadow``: ``shadow.size`` 512..4096, ``shadow.pcf_taps`` 1,4,9,16; reference
  ``shadow.size=8192 shadow.pcf_taps=64`` (``--shadow-reference`` to change the size).
- ``ibl``: ``ibl.samples`` 16,64,256, ``ibl.lut_size`` 16,32,64; reference
  ``ibl.samples=4096 ibl.lut_size=256``; ``-p ibl.static=0`` under every setting so the
  IBL build (normally once per run) is timed every frame.
- ``rt``: ``rt_standalone`` on ``rt_living_room``: ``rt.max_depth`` 1..8; reference depth 16.
- ``clusters``: ``clustered`` on ``many_lights``: ``clusters.tile`` 16,32,64,128,
  ``clusters.slices`` 8,16,24,48; reference ``clusters.tile=16 clusters.slices=48``.
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

GRAPH = "surgery"
SCENES = ROOT / "graphs" / "scenes"


@dataclass(frozen=True)
class Group:
    name: str
    knobs: tuple[str, ...]
    reference: tuple[str, ...]
    passes: tuple[str, ...]  # the passes whose time the knobs move
    hdr: str | None  # image the HDR metrics compare
    base: tuple[str, ...] = field(default=())
    why: str = ""
    graph: str = GRAPH
    scene: str | None = None  # None: the graph's own


def groups(shadow_reference: int) -> dict[str, Group]:
    return {g.name: g for g in (
        Group("hbao", ("hbao.directions=2,4,8,16", "hbao.steps=2,4,8", "hbao.scale=0.25,0.5"),
              ("hbao.scale=1", "hbao.directions=32", "hbao.steps=32"),
              ("hbao_downsample", "hbao", "hbao_upsample"), "ao",
              why="full-resolution HBAO with 32 directions x 32 steps"),
        Group("sss", ("sss.samples=11,17,25",), ("sss.kernel=2d", "sss.samples=25"),
              ("sss_blur_h", "sss_blur_v"), "diffuse",
              why="the non-separable 2D convolution of the same diffusion profile (513 taps)"),
        Group("bloom", ("bloom.radius=8,12,16,24", "bloom.scale=0.25,0.5"), ("bloom.scale=1", "bloom.radius=24"),
              ("bloom_bright", "bloom_blur_h", "bloom_blur_v", "bloom_combine"), "hdr",
              why="the full-resolution Gaussian (sigma 8 px) truncated at 3 sigma"),
        Group("shadow", ("shadow.size=512,1024,2048,4096", "shadow.pcf_taps=1,4,9,16"),
              (f"shadow.size={shadow_reference}", "shadow.pcf_taps=64"), ("shadow", "forward"), "hdr",
              why=f"{shadow_reference}^2 shadow maps with 8x8 PCF (PCF runs in forward)"),
        Group("ibl", ("ibl.samples=16,64,256", "ibl.lut_size=16,32,64"), ("ibl.samples=4096", "ibl.lut_size=256"),
              ("ibl_brdf_lut", "ibl_prefilter"), "hdr", base=("ibl.static=0",),
              why="4096 importance samples and a 256^2 split-sum LUT; built every frame (ibl.static=0) to time it"),
        Group("rt", ("rt.max_depth=1,2,3,4,5,6,7,8",), ("rt.max_depth=16",), ("trace",), None,
              why="16 bounces (the living room's glass and mirrors keep rays alive)",
              graph="rt_standalone", scene=str(SCENES / "rt_living_room.yaml")),
        Group("clusters", ("clusters.tile=16,32,64,128", "clusters.slices=8,16,24,48"),
              ("clusters.tile=16", "clusters.slices=48"), ("cluster_build", "light_assign", "forward"), None,
              why="the finest froxels (the light lists are exact: settings differ from it by float rounding)",
              graph="clustered", scene=str(SCENES / "many_lights.yaml")),
    )}


def request(group: Group, *, size: tuple[int, int], frames: int, validate: bool):
    """The group's ``rgraph sweep`` request."""
    from rgraph.sweep.runner import SweepRequest
    from rgraph.sweep.settings import parse_assignments, parse_knob

    return SweepRequest(graph=group.graph, scene=group.scene, knobs=[parse_knob(k) for k in group.knobs],
                        base=parse_assignments(list(group.base), "-p"),
                        reference=parse_assignments(list(group.reference), "--reference"),
                        size=size, frames=frames, hdr=group.hdr, validate=validate)


def write_group(result, out: Path):
    """What ``rgraph sweep`` writes: returns (plot paths by knob, metric plotted)."""
    from rgraph.sweep.writers import write_sweep

    written, metric = write_sweep(result, out)
    plots = {k.removeprefix("plot:"): p.relative_to(out).as_posix() for k, p in written.items() if k.startswith("plot:")}
    return plots, metric


def run_group(group: Group, out: Path, *, size: tuple[int, int], frames: int, validate: bool, progress: bool):
    """One ``rgraph sweep`` in this process: returns (SweepResult, plot paths by knob, metric plotted)."""
    from rgraph.sweep.runner import run_sweep

    result = run_sweep(request(group, size=size, frames=frames, validate=validate), out, progress=progress)
    return (result, *write_group(result, out))


def group_ms(row, passes: tuple[str, ...]) -> float | None:
    values = [row.pass_ms.get(p) for p in passes]
    return None if any(v is None for v in values) else float(sum(values))


def group_markdown(group: Group, result, plots: dict[str, str], metric: str | None) -> list[str]:
    from rgraph.sweep.compare import METRICS
    from rgraph.sweep.plots import METRIC_TITLES
    from rgraph.sweep.writers import fmt

    shown = [m for m in METRICS if any(r.metrics.get(m) is not None for r in result.rows)]
    lines = [f"## {group.name}", "",
             f"- graph `{group.graph}`" + (f" on `{Path(group.scene).stem}`" if group.scene else " with its scene"),
             "- knobs (one at a time from the defaults): " + "; ".join(f"`{k}`" for k in group.knobs),
             f"- reference: `{' '.join(group.reference)}`: {group.why}",
             ]
    if group.base:
        lines.append(f"- under every setting: `{' '.join(group.base)}`")
    lines += [f"- HDR metrics on `{group.hdr}`; LDR metrics on the output `{result.output_name}`",
              f"- full tables, per-pass times, images and error maps: [{group.name}/sweep.md]({group.name}/sweep.md)", ""]
    lines += [f"- {n}" for n in result.notes]
    if result.notes:
        lines.append("")
    header = ["setting", f"{'+'.join(group.passes)} ms", "frame ms"] + [METRIC_TITLES.get(m, m) for m in shown]
    lines += ["| " + " | ".join(header) + " |", "|---|" + "---:|" * (len(header) - 1)]
    for row in result.rows:
        label = row.setting.label
        if row.setting.role == "knob" and all(result.defaults.get(k) == row.params.get(k) for k in row.setting.varied):
            label += " (default)"
        lines.append("| " + " | ".join([label, fmt(group_ms(row, group.passes)), fmt(row.total_ms)]
                                       + [fmt(row.metrics.get(m)) for m in shown]) + " |")
    lines.append("")
    if plots:
        lines += [f"Pareto plots ({METRIC_TITLES.get(metric or '', metric)} vs the GPU ms of the passes each knob "
                  "changes: " + "; ".join(f"`{k}`: {'+'.join(v) or 'frame'}" for k, v in result.knob_passes.items())
                  + "):", ""]
        lines += [f"![{group.name}: {knob}]({group.name}/{path})" for knob, path in plots.items()] + [""]
    return lines


def parse_size(text: str) -> tuple[int, int]:
    w, _, h = text.lower().partition("x")
    return int(w), int(h)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="1920x1080", help="WxH (default 1920x1080)")
    parser.add_argument("--frames", type=int, default=100, help="frames per setting, times are medians (default 100)")
    parser.add_argument("--groups", default=",".join(groups(8192)), help="comma-separated subset")
    parser.add_argument("--shadow-reference", type=int, default=8192, help="reference shadow map size (default 8192)")
    parser.add_argument("--validate", action="store_true", help="validation layers on (times not representative)")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="every setting of every group in its own worker process, through one pool of N")
    parser.add_argument("--per-worker", type=int, default=1, metavar="K",
                        help="with --workers: settings a worker process renders, one after another on one "
                             "device, before a fresh process takes its place (default 1)")
    parser.add_argument("--no-progress", dest="progress", action="store_false")
    parser.add_argument("-o", "--out", type=Path, required=True, help="output folder")
    args = parser.parse_args(argv)
    command = "PYTHONPATH=. python3 benchmarks/sweeps.py " + shlex.join(sys.argv[1:] if argv is None else argv)
    size = parse_size(args.size)
    known = groups(args.shadow_reference)
    chosen = [g.strip() for g in args.groups.split(",") if g.strip()]
    unknown = [g for g in chosen if g not in known]
    if unknown:
        parser.error(f"unknown group(s) {', '.join(unknown)}; known: {', '.join(known)}")
    if args.workers is not None and args.workers < 1:
        parser.error("--workers must be at least 1")
    if args.per_worker < 1:
        parser.error("--per-worker must be at least 1")

    from rgraph.errors import RGraphError
    from rgraph.vk.errors import ExecutionError, VulkanUnavailable

    progress = args.progress and sys.stderr.isatty()
    done: dict[str, tuple] = {}  # group -> (result, plots, metric)
    failures = 0
    start = time.perf_counter()

    def report(name: str, result, seconds: float, since: str = "") -> None:
        nonlocal failures
        for label, why in result.failures.items():
            print(f"sweeps: {name}: setting {label} failed: {why}", file=sys.stderr)
        failures += len(result.failures)
        print(f"sweeps: {name}: {len(result.rows)} settings ({result.renderings} renderings) in "
              f"{seconds:.1f} s{since}", file=sys.stderr, flush=True)

    try:
        if args.workers is None:
            for name in chosen:
                t0 = time.perf_counter()
                done[name] = run_group(known[name], args.out / name, size=size, frames=args.frames,
                                       validate=args.validate, progress=progress)
                report(name, done[name][0], time.perf_counter() - t0)
            how = "one process"
        else:
            how = run_pool([known[n] for n in chosen], args, size, progress, done, report, start)
    except (RGraphError, ExecutionError, VulkanUnavailable) as exc:
        print(f"sweeps: error: {exc}", file=sys.stderr)
        return 2
    failures += len([n for n in chosen if n not in done])
    sections: list[str] = []
    for name in chosen:
        if name in done:
            sections += group_markdown(known[name], *done[name])
    results = [done[n][0] for n in chosen if n in done]
    device = results[0].device if results else "?"
    messages = sum(len(r.messages()) for r in results)
    renderings = sum(r.renderings for r in results)
    wall = time.perf_counter() - start
    head = ["# Accuracy vs time: the committed sweeps", "",
            f"- device: {device}; size {size[0]}x{size[1]}; GPU times are medians of {args.frames} frames"
            + (" (under validation: not representative)" if args.validate else ""),
            f"- command: `{command}`",
            "- each knob moves alone from the graph's defaults; every error is "
            "against the group's reference setting, which is more accurate than any shipping setting "
            "(the truth the knob approximates), not against the knob's highest value",
            f"- wall time {wall:.0f} s for {renderings} renderings ({how})"
            + (f"; {messages} validation message(s)" if args.validate else ""),
            ""]
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "accuracy-vs-time.md"
    path.write_text("\n".join(head + sections) + "\n")
    print(f"sweeps: {renderings} renderings in {wall:.1f} s ({how}); wrote {path}", file=sys.stderr)
    return 1 if failures or (args.validate and messages) else 0


def run_pool(chosen: list[Group], args, size, progress: bool, done: dict, report, start: float) -> str:
    """Every group through one pool of ``args.workers`` processes; fills ``done`` as groups
    finish (each group's outputs written then). Returns the pool's description."""
    from rgraph.sweep.parallel import make_executor
    from rgraph.sweep.pool import Group as PoolGroup
    from rgraph.sweep.pool import run_groups

    pool = [PoolGroup(g.name, request(g, size=size, frames=args.frames, validate=args.validate), args.out / g.name)
            for g in chosen]

    def finished(group: PoolGroup, result) -> None:
        if isinstance(result, Exception):
            print(f"sweeps: {group.name}: error: {result}", file=sys.stderr, flush=True)
            return
        done[group.name] = (result, *write_group(result, group.out_dir))
        report(group.name, result, time.perf_counter() - start, " (done since the start)")

    with make_executor(args.workers, tasks_per_worker=args.per_worker) as executor:
        run_groups(pool, executor, done=finished, progress=progress)
        return f"one pool of {executor.description} for all groups"


if __name__ == "__main__":
    sys.exit(main())
