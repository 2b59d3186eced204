"""What accuracy costs in time (issue 6 item 1): the surgery sweeps, one knob at a time,
each group against a reference setting more accurate than any shipping setting.

    PYTHONPATH=. python3 benchmarks/sweeps.py [--size 1920x1080] [--frames 100]
        [--groups hbao,sss,bloom,shadow,ibl] [--workers N] [--validate] -o DIR

Runs ``rgraph sweep`` (``rgraph.sweep.runner``) once per group into ``DIR/<group>``
(sweep.csv, sweep.md, Pareto plots, images, error maps), then writes
``DIR/accuracy-vs-time.md``: the device, the exact command line, and per group its
reference, a table (the group's own passes' GPU ms, the frame's, and the errors) and links
to its plots. HDR metrics are on the image the group's passes produce (``--hdr``): the AO
image for HBAO, the diffuse image after SSS for SSS, the HDR image for the others.

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


@dataclass(frozen=True)
class Group:
    name: str
    knobs: tuple[str, ...]
    reference: tuple[str, ...]
    passes: tuple[str, ...]  # the passes whose time the knobs move
    hdr: str  # image the HDR metrics compare
    base: tuple[str, ...] = field(default=())
    why: str = ""


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
    )}


def run_group(group: Group, out: Path, *, size: tuple[int, int], frames: int, validate: bool, progress: bool,
              executor=None):
    """One ``rgraph sweep`` (``executor``: its settings in worker processes): returns
    (SweepResult, plot paths by knob, metric plotted)."""
    from rgraph.sweep import flip
    from rgraph.sweep.runner import SweepRequest, run_sweep
    from rgraph.sweep.settings import parse_assignments, parse_knob
    from rgraph.sweep.writers import plot_metric, write_all

    request = SweepRequest(graph=GRAPH, knobs=[parse_knob(k) for k in group.knobs],
                           base=parse_assignments(list(group.base), "-p"),
                           reference=parse_assignments(list(group.reference), "--reference"),
                           size=size, frames=frames, hdr=group.hdr, validate=validate)
    result = run_sweep(request, out, progress=progress, executor=executor)
    note = flip.missing_note()
    if note and note not in result.notes:
        result.notes.append(note)
    metric = plot_metric(result)
    written = write_all(result, out, metric)
    plots = {k.removeprefix("plot:"): p.relative_to(out).as_posix() for k, p in written.items() if k.startswith("plot:")}
    return result, plots, metric


def group_ms(row, passes: tuple[str, ...]) -> float | None:
    values = [row.pass_ms.get(p) for p in passes]
    return None if any(v is None for v in values) else float(sum(values))


def group_markdown(group: Group, result, plots: dict[str, str], metric: str | None) -> list[str]:
    from rgraph.sweep.compare import METRICS
    from rgraph.sweep.plots import METRIC_TITLES
    from rgraph.sweep.writers import fmt

    shown = [m for m in METRICS if any(r.metrics.get(m) is not None for r in result.rows)]
    lines = [f"## {group.name}", "",
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
    parser.add_argument("--groups", default="hbao,sss,bloom,shadow,ibl", help="comma-separated subset")
    parser.add_argument("--shadow-reference", type=int, default=8192, help="reference shadow map size (default 8192)")
    parser.add_argument("--validate", action="store_true", help="validation layers on (times not representative)")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="every setting in its own worker process, N at a time (rgraph sweep --workers)")
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

    from rgraph.errors import RGraphError
    from rgraph.sweep.parallel import make_executor
    from rgraph.vk.errors import ExecutionError, VulkanUnavailable

    if args.workers is not None and args.workers < 1:
        parser.error("--workers must be at least 1")
    executor = make_executor(args.workers)

    sections: list[str] = []
    device = "?"
    messages = failures = 0
    start = time.perf_counter()
    for name in chosen:
        group = known[name]
        t0 = time.perf_counter()
        try:
            result, plots, metric = run_group(group, args.out / name, size=size, frames=args.frames,
                                              validate=args.validate, progress=args.progress and sys.stderr.isatty(),
                                              executor=executor)
        except (RGraphError, ExecutionError, VulkanUnavailable) as exc:
            print(f"sweeps: {name}: error: {exc}", file=sys.stderr)
            return 2
        device = result.device
        messages += len(result.messages())
        for label, why in result.failures.items():
            print(f"sweeps: {name}: setting {label} failed: {why}", file=sys.stderr)
        failures += len(result.failures)
        sections += group_markdown(group, result, plots, metric)
        print(f"sweeps: {name}: {len(result.rows)} settings ({result.renderings} renderings) in "
              f"{time.perf_counter() - t0:.1f} s", file=sys.stderr)
    head = ["# Accuracy vs time: the surgery sweeps", "",
            f"- device: {device}; size {size[0]}x{size[1]}; GPU times are medians of {args.frames} frames"
            + (" (under validation: not representative)" if args.validate else ""),
            f"- command: `{command}`",
            f"- graph `{GRAPH}` with its scene; each knob moves alone from the graph's defaults; every error is "
            "against the group's reference setting, which is more accurate than any shipping setting "
            "(the truth the knob approximates), not against the knob's highest value",
            f"- wall time {time.perf_counter() - start:.0f} s"
            + (f" ({executor.description})" if executor else " (one process)")
            + (f"; {messages} validation message(s)" if args.validate else ""),
            ""]
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "accuracy-vs-time.md"
    path.write_text("\n".join(head + sections) + "\n")
    print(f"sweeps: wrote {path}", file=sys.stderr)
    return 1 if failures or (args.validate and messages) else 0


if __name__ == "__main__":
    sys.exit(main())
