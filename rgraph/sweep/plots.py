"""Pareto plots (error vs GPU milliseconds of the knob's passes, one per knob) and
error-map images."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from rgraph.sweep import flip, metrics
from rgraph.sweep.compare import LOWER_IS_BETTER
from rgraph.sweep.images import save_png
from rgraph.sweep.pareto import pareto_front

METRIC_TITLES = {"psnr": "PSNR (dB)", "ssim": "SSIM", "flip": "mean FLIP", "hdr_rel_mse": "HDR relative MSE",
                 "hdr_log_psnr": "HDR log-PSNR (dB)", "hdr_flip": "mean HDR-FLIP"}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _plottable(values: list[float | None]) -> tuple[list[float | None], float | None]:
    """Infinite values (identical to the reference) moved just past the finite range, and
    where they went (None when there were none)."""
    finite = [v for v in values if v is not None and math.isfinite(v)]
    if not any(v is not None and math.isinf(v) for v in values):
        return values, None
    top = (max(finite) + max(0.1 * abs(max(finite)), 1.0)) if finite else 1.0
    return [top if v is not None and math.isinf(v) else v for v in values], top


def pareto_plot(path: Path, *, knob: str, labels: list[str], ms: list[float | None], error: list[float | None],
                defaults: list[bool], metric: str, title: str, reference_ms: float | None = None,
                xlabel: str = "GPU time per frame (ms, median)") -> bool:
    """Write one knob's plot; False (nothing written) when no point has both coordinates."""
    y, inf_at = _plottable(error)
    points = [(i, t, e) for i, (t, e) in enumerate(zip(ms, y, strict=True)) if t is not None and e is not None]
    if not points:
        return False
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=110)
    try:
        xs = [t for _i, t, _e in points]
        ys = [e for _i, _t, e in points]
        ax.scatter(xs, ys, color="tab:blue", zorder=3, label="setting")
        star = [(t, e) for i, t, e in points if defaults[i]]
        if star:
            ax.scatter(*zip(*star, strict=True), s=220, facecolors="none", edgecolors="tab:red", linewidths=1.8,
                       zorder=4, label=f"graph default {knob}")
        for i, t, e in points:
            ax.annotate(labels[i] + ("" if inf_at is None or e != inf_at else " (identical)"), (t, e),
                        textcoords="offset points", xytext=(6, 5), fontsize=8)
        front = pareto_front(ms, y, lower_is_better=LOWER_IS_BETTER.get(metric, True))
        if front:
            ax.step([ms[i] for i in front], [y[i] for i in front], where="post", color="tab:green",
                    linewidth=1.4, zorder=2, label="Pareto front")
        lo, hi = min(xs), max(xs)
        pad = 0.08 * (hi - lo) if hi > lo else 0.05 * max(abs(hi), 1e-3)
        if reference_ms is not None and lo - pad <= reference_ms <= hi + pad:
            ax.axvline(reference_ms, color="grey", linestyle="--", linewidth=1, label=f"reference {reference_ms:.3g} ms")
        elif reference_ms is not None:  # far away: say where, keep the settings readable
            ax.plot([], [], color="grey", linestyle="--", label=f"reference {reference_ms:.3g} ms (off axis)")
        ax.set_xlim(lo - pad, hi + pad)
        positive = [e for e in ys if e > 0]
        if len(positive) == len(ys) and max(ys) >= 20 * min(ys):
            ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        better = "lower" if LOWER_IS_BETTER.get(metric, True) else "higher"
        ax.set_ylabel(f"{METRIC_TITLES.get(metric, metric)} vs reference ({better} is better)")
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path)
    finally:
        plt.close(fig)
    return True


def error_map_pngs(slug: str, reference: np.ndarray, test: np.ndarray) -> dict[str, bytes]:
    """Per-pixel error maps of display images as PNG bytes by path (relative to the output
    folder): the |difference| heatmap, and FLIP (magma, its own [0, 1] scale) when
    flip-evaluator is installed. Pure: a worker process draws them (``--workers``)."""
    import io

    from rgraph.sweep.images import png_bytes

    maps: dict[str, bytes] = {}
    diff = metrics.abs_difference(reference, test)
    plt = _pyplot()
    h, w = diff.shape
    fig, ax = plt.subplots(figsize=(max(3.0, 6.0 * w / max(w, h)) + 1.2, max(3.0, 6.0 * h / max(w, h))), dpi=110)
    try:
        shown = ax.imshow(diff, cmap="magma", vmin=0.0, vmax=max(float(diff.max()), 1e-6), interpolation="nearest")
        fig.colorbar(shown, ax=ax, label="mean |difference| of display values")
        ax.set_title(f"{slug}: max {diff.max():.4g}, mean {diff.mean():.4g}", fontsize=9)
        ax.set_axis_off()
        fig.tight_layout()
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png")
        maps[f"errors/{slug}_absdiff.png"] = buffer.getvalue()
    finally:
        plt.close(fig)
    out = flip.flip_ldr(reference, test, magma=True)
    if out is not None:
        maps[f"errors/{slug}_flip.png"] = png_bytes(out[0])
    return maps


def write_error_maps(out_dir: Path, slug: str, reference: np.ndarray, test: np.ndarray,
                     drawn: dict[str, bytes] | None = None) -> list[str]:
    """Write :func:`error_map_pngs` (``drawn``: already drawn, e.g. by a worker) under
    ``out_dir``. Returns their paths relative to ``out_dir``."""
    maps = error_map_pngs(slug, reference, test) if drawn is None else drawn
    for rel, data in maps.items():
        save_png(out_dir / rel, data)
    return list(maps)
