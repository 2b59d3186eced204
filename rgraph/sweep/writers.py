"""A sweep's results as ``sweep.csv``, ``sweep.md`` and one Pareto plot per knob (error
against the GPU time of the passes the knob changes: :mod:`rgraph.sweep.affected`)."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

from rgraph.sweep.affected import passes_ms
from rgraph.sweep.compare import HDR_METRICS, METRICS
from rgraph.sweep.plots import METRIC_TITLES, pareto_plot
from rgraph.sweep.runner import Row, SweepResult


def fmt(value: Any) -> str:
    """CSV/Markdown text of a figure: '' for missing, 'inf' for infinite, 6 significant digits."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return f"{value:.6g}"
    return str(value)


def knob_names(result: SweepResult) -> list[str]:
    return [k.name for k in result.request.knobs]


def row_knob(row: Row) -> tuple[str, str]:
    """(knob, value) columns: the varied knob(s) and value(s), or '' and the role."""
    if not row.setting.varied:
        return "", row.setting.role
    return ",".join(row.setting.varied), ",".join(row.setting.varied.values())


def csv_header(result: SweepResult) -> list[str]:
    return (["setting", "role", "knob", "value"] + [f"param.{k}" for k in knob_names(result)]
            + [f"ms.{p}" for p in result.pass_names] + ["total_ms"] + list(METRICS) + ["messages", "image"])


def write_csv(result: SweepResult, path: Path) -> None:
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(csv_header(result))
        for row in result.rows:
            knob, value = row_knob(row)
            writer.writerow([row.setting.label, row.setting.role, knob, value]
                            + [fmt(row.params.get(k)) for k in knob_names(result)]
                            + [fmt(row.pass_ms.get(p)) for p in result.pass_names]
                            + [fmt(row.total_ms)] + [fmt(row.metrics.get(m)) for m in METRICS]
                            + [len(row.messages), row.image or ""])


def plot_metric(result: SweepResult, wanted: str | None = None) -> str | None:
    """The metric the plots show: ``wanted`` when some row has it, else the first of
    flip, ssim, psnr, hdr_flip, hdr_rel_mse with values."""
    order = ([wanted] if wanted else []) + ["flip", "ssim", "psnr", "hdr_flip", "hdr_rel_mse", "hdr_log_psnr"]
    for metric in order:
        if any(r.metrics.get(metric) is not None for r in result.rows):
            return metric
    return None


def knob_axis(result: SweepResult, knob: str) -> tuple[list[str], str]:
    """The passes a knob's plot times and its axis label (the whole frame when the knob
    changes no pass)."""
    passes = result.knob_passes.get(knob, [])
    if not passes:
        return [], "GPU time per frame (ms, median)"
    return passes, f"GPU time of {'+'.join(passes)} (ms, median)"


def row_ms(row: Row, passes: list[str]) -> float | None:
    """The row's GPU ms of ``passes`` (its frame's when none)."""
    return passes_ms(row.pass_ms, passes) if passes else row.total_ms


def write_plots(result: SweepResult, out_dir: Path, metric: str | None) -> dict[str, str]:
    """One Pareto plot per knob, against the GPU time of the passes it changes: knob -> PNG
    path relative to ``out_dir``."""
    if metric is None:
        return {}
    reference = next((r for r in result.rows if r.setting.role == "reference"), None)
    written: dict[str, str] = {}
    frames = result.request.frames
    for knob in knob_names(result):
        rows = result.rows_for_knob(knob)
        passes, xlabel = knob_axis(result, knob)
        rel = f"pareto_{knob}.png"
        ok = pareto_plot(
            out_dir / rel, knob=knob, labels=[fmt(r.params.get(knob)) for r in rows],
            ms=[row_ms(r, passes) for r in rows], error=[r.metrics.get(metric) for r in rows],
            defaults=[r.params.get(knob) == result.defaults.get(knob) for r in rows], metric=metric,
            title=f"{result.graph_name}: {knob} ({result.device}, median of {frames} frames)",
            reference_ms=row_ms(reference, passes) if reference else None, xlabel=xlabel)
        if ok:
            written[knob] = rel
    return written


def _table(header: list[str], rows: list[list[str]], right_from: int) -> list[str]:
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join("---:" if i >= right_from else "---" for i in range(len(header))) + "|"]
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    return lines


def markdown(result: SweepResult, plots: dict[str, str], metric: str | None) -> str:
    req = result.request
    shown = [m for m in METRICS if any(r.metrics.get(m) is not None for r in result.rows)]
    ref = ", ".join(f"{k}={v}" for k, v in req.reference.items()) or "the defaults"
    lines = [f"# Sweep of `{result.graph_name}`", "",
             f"- device: {result.device}; size {req.size[0]}x{req.size[1]}; scene {result.scene or '-'}; "
             f"GPU times are medians of {req.frames} frames" + (" (under validation)" if req.validate else ""),
             "- knobs: " + "; ".join(f"`{k.name}` = {', '.join(k.values)} (default {fmt(result.defaults.get(k.name))})"
                                      for k in req.knobs),
             f"- mode: {'grid (every combination)' if req.grid else 'one knob at a time from the defaults'}",
             f"- reference: {ref}" + ("; `-p` under every setting: "
                                       + ", ".join(f"{k}={v}" for k, v in req.base.items()) if req.base else ""),
             f"- LDR metrics on output `{result.output_name}` (display-encoded); "
             + (f"HDR metrics on `{req.hdr}` (linear)" if req.hdr else "no HDR resource asked (--hdr)"),
             ""]
    if result.notes:
        lines += ["Notes:", ""] + [f"- {n}" for n in result.notes] + [""]
    header = ["setting", "total ms"] + [METRIC_TITLES.get(m, m) for m in shown] + ["messages"]
    body = [[r.setting.label, fmt(r.total_ms)] + [fmt(r.metrics.get(m)) for m in shown] + [str(len(r.messages))]
            for r in result.rows]
    lines += ["## Settings", ""] + _table(header, body, 1) + [""]
    lines += ["## GPU ms per pass", ""]
    header = ["pass"] + [r.setting.label for r in result.rows]
    body = [[p] + [fmt(r.pass_ms.get(p)) for r in result.rows] for p in result.pass_names]
    lines += _table(header, body, 1) + [""]
    if result.knob_passes:
        lines += ["## Passes each knob changes (the time axis of its plot)", ""]
        lines += [f"- `{k}`: " + (", ".join(f"`{p}`" for p in v) if v else "none found (plotted against the frame)")
                  for k, v in result.knob_passes.items()] + [""]
    if plots:
        lines += [f"## Pareto plots ({METRIC_TITLES.get(metric or '', metric)} vs GPU ms of the knob's passes)", ""]
        lines += [f"![{knob}]({path})" for knob, path in plots.items()] + [""]
    if result.error_maps:
        lines += ["## Error maps (lowest and highest value of each knob)", ""]
        for label, paths in result.error_maps.items():
            lines.append(f"- `{label}`: " + ", ".join(f"[{Path(p).name}]({p})" for p in paths))
        lines.append("")
    if any(m in HDR_METRICS for m in shown):
        lines += ["HDR metrics: relative MSE = mean((t-r)^2/(r^2+0.01)); log-PSNR = PSNR of log2(1+x) with the "
                  "reference's largest log value as peak; HDR-FLIP from flip-evaluator.", ""]
    return "\n".join(lines)


def write_all(result: SweepResult, out_dir: Path, metric: str | None = None) -> dict[str, Path]:
    """sweep.csv, pareto_<knob>.png, sweep.md; returns what was written."""
    out_dir.mkdir(parents=True, exist_ok=True)
    write_csv(result, out_dir / "sweep.csv")
    chosen = plot_metric(result, metric)
    plots = write_plots(result, out_dir, chosen)
    (out_dir / "sweep.md").write_text(markdown(result, plots, chosen) + "\n")
    return {"csv": out_dir / "sweep.csv", "md": out_dir / "sweep.md",
            **{f"plot:{k}": out_dir / v for k, v in plots.items()}}


def write_sweep(result: SweepResult, out_dir: Path, wanted: str | None = None) -> tuple[dict[str, Path], str | None]:
    """What ``rgraph sweep`` writes for ``result``: its notes completed (FLIP missing, an
    empty ``--metric``), then :func:`write_all`. Returns (what was written, metric plotted)."""
    from rgraph.sweep import flip

    note = flip.missing_note()
    if note and note not in result.notes:
        result.notes.append(note)
    chosen = plot_metric(result, wanted)
    if wanted and chosen != wanted:
        result.notes.append(f"--metric {wanted}: no values; plots show {chosen or 'nothing'}")
    return write_all(result, out_dir, chosen), chosen
