"""sweep.csv, sweep.md, Pareto plots and error maps from a hand-built sweep result."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from rgraph.sweep import flip
from rgraph.sweep.compare import METRICS
from rgraph.sweep.plots import pareto_plot, write_error_maps
from rgraph.sweep.runner import Row, SweepRequest, SweepResult
from rgraph.sweep.settings import Setting, parse_knob
from rgraph.sweep.writers import fmt, markdown, plot_metric, write_all

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _row(label, role, varied, params, total, psnr, flip_value, rendering, messages=()):
    m = dict.fromkeys(METRICS)
    m.update(psnr=psnr, ssim=None if psnr is None else (1.0 if math.isinf(psnr) else 0.9), flip=flip_value)
    return Row(Setting(label, role, dict(varied), dict(varied)), params, {"a": total / 4, "b": 3 * total / 4},
               total, m, list(messages), f"images/{label}.png", rendering)


def _result(grid=False):
    knobs = [parse_knob("q.samples=1,4"), parse_knob("q.steps=2")]
    rows = [
        _row("reference", "reference", {}, {"q.samples": 16, "q.steps": 8}, 10.0, math.inf, 0.0, 0),
        _row("default", "default", {}, {"q.samples": 2, "q.steps": 4}, 3.0, 30.0, 0.05, 1),
        _row("q.samples=1", "knob", {"q.samples": "1"}, {"q.samples": 1, "q.steps": 4}, 2.0, 20.0, 0.2, 2,
             ["VUID-x: something"]),
        _row("q.samples=4", "knob", {"q.samples": "4"}, {"q.samples": 4, "q.steps": 4}, 5.0, 40.0, 0.01, 3),
        _row("q.steps=2", "knob", {"q.steps": "2"}, {"q.samples": 2, "q.steps": 2}, 2.5, None, None, 4),
    ]
    request = SweepRequest(graph="g", knobs=knobs, reference={"q.samples": "16", "q.steps": "8"}, size=(8, 8),
                           frames=3, grid=grid)
    return SweepResult(request=request, graph_name="g", scene="s", device="dev", defaults={"q.samples": 2, "q.steps": 4},
                       rows=rows, pass_names=["a", "b"], notes=["a note"],
                       error_maps={"q.samples=1": ["errors/q.samples=1_absdiff.png"]}, output_name="color")


def test_fmt():
    assert fmt(None) == "" and fmt(math.inf) == "inf" and fmt(-math.inf) == "-inf" and fmt(math.nan) == "nan"
    assert fmt(0.123456789) == "0.123457" and fmt(3) == "3" and fmt(True) == "true"


def test_csv_markdown_and_plots(tmp_path):
    result = _result()
    written = write_all(result, tmp_path)
    with (tmp_path / "sweep.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["setting"] for r in rows] == ["reference", "default", "q.samples=1", "q.samples=4", "q.steps=2"]
    assert list(rows[0])[:6] == ["setting", "role", "knob", "value", "param.q.samples", "param.q.steps"]
    assert rows[0]["psnr"] == "inf" and rows[0]["value"] == "reference" and rows[0]["knob"] == ""
    assert rows[2]["knob"] == "q.samples" and rows[2]["value"] == "1" and rows[2]["param.q.steps"] == "4"
    assert rows[2]["ms.a"] == "0.5" and rows[2]["ms.b"] == "1.5" and rows[2]["total_ms"] == "2"
    assert rows[2]["messages"] == "1" and rows[4]["psnr"] == "" and rows[4]["flip"] == ""
    assert {"flip", "ssim", "hdr_rel_mse", "hdr_log_psnr", "hdr_flip"} <= set(rows[0])
    md = (tmp_path / "sweep.md").read_text()
    assert "| q.samples=4 | 5 | 40 | 0.9 | 0.01 | 0 |" in md
    assert "| a | 2.5 | 0.75 | 0.5 | 1.25 | 0.625 |" in md
    assert "- a note" in md and "(default 2)" in md and "![q.samples](pareto_q.samples.png)" in md
    assert "errors/q.samples=1_absdiff.png" in md
    assert "HDR relative MSE" not in md  # columns without values are left out
    for knob in ("q.samples", "q.steps"):
        assert written[f"plot:{knob}"].read_bytes()[:8] == PNG_MAGIC
    assert "plot:q.steps" in written  # the default row gives its second point


def test_rows_for_knob_adds_the_default_once():
    result = _result()
    assert [r.setting.label for r in result.rows_for_knob("q.samples")] == ["q.samples=1", "q.samples=4", "default"]
    assert result.renderings == 5
    assert result.messages() == [("q.samples=1", "VUID-x: something")]
    assert [r.setting.label for r in _result(grid=True).rows_for_knob("q.samples")] == ["q.samples=1", "q.samples=4"]


def test_plot_metric_falls_back():
    result = _result()
    assert plot_metric(result) == "flip"
    assert plot_metric(result, "psnr") == "psnr"
    assert plot_metric(result, "hdr_flip") == "flip"  # no hdr values: first metric with values
    for row in result.rows:
        row.metrics = dict.fromkeys(METRICS)
    assert plot_metric(result) is None
    assert "Pareto" not in markdown(result, {}, None)


def test_pareto_plot_needs_points(tmp_path):
    path = tmp_path / "p.png"
    assert not pareto_plot(path, knob="k", labels=["1"], ms=[None], error=[0.1], defaults=[False], metric="flip",
                           title="t")
    assert not path.exists()
    assert pareto_plot(path, knob="k", labels=["1", "2"], ms=[1.0, 2.0], error=[math.inf, 30.0],
                       defaults=[True, False], metric="psnr", title="t", reference_ms=3.0)
    assert path.read_bytes()[:8] == PNG_MAGIC


def test_error_maps(tmp_path):
    rng = np.random.default_rng(0)
    ref = rng.random((12, 16, 3))
    paths = write_error_maps(tmp_path, "k=1", ref, np.clip(ref + 0.1, 0, 1))
    assert paths[0] == "errors/k=1_absdiff.png"
    assert (tmp_path / paths[0]).read_bytes()[:8] == PNG_MAGIC
    if flip.available():
        import matplotlib.image

        assert paths[1] == "errors/k=1_flip.png"
        assert matplotlib.image.imread(tmp_path / paths[1]).shape[:2] == (12, 16)  # native resolution
    else:
        assert len(paths) == 1


@pytest.mark.parametrize("shape", [(5, 7), (5, 7, 1), (5, 7, 2), (5, 7, 4)])
def test_channels_become_rgb(shape):
    from rgraph.sweep.images import display, rgb

    a = np.full(shape, 0.5, dtype=np.float32)
    assert rgb(a).shape == (5, 7, 3)
    assert display(a, "R8G8B8A8_SRGB").max() == pytest.approx(0.7354, abs=1e-4)
    assert display(a * 4, "R16G16B16A16_SFLOAT").max() == 1.0
