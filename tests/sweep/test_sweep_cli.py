"""``rgraph sweep`` end to end on lavapipe under validation: a graph whose image depends on
its knob (a supersampled zone plate), the bundled surgery graph, and bad input."""

from __future__ import annotations

import math

import pytest
import sweep_fixtures.passes as zoneplate  # registers the fixture's pass implementations
from sweep_helpers import rows as _rows
from sweep_helpers import sweep as _sweep

from rgraph.sweep import flip

pytestmark = pytest.mark.vulkan


def test_zoneplate_sweep_measures_real_error(tmp_path, capsys):
    out = tmp_path / "sweep"
    rc = _sweep([str(zoneplate.GRAPH), "--size", "64x64", "--frames", "2", "--knob", "aa.samples=1,4",
                 "--reference", "aa.samples=12", "--hdr", "hdr", "--validate", "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 0, err
    assert "0 validation message(s)" in err
    rows = _rows(out)
    assert list(rows) == ["reference", "default", "aa.samples=1", "aa.samples=4"]
    assert all(r["messages"] == "0" for r in rows.values())
    ref, low, high = rows["reference"], rows["aa.samples=1"], rows["aa.samples=4"]
    assert ref["psnr"] == "inf" and float(ref["ssim"]) == 1.0 and ref["hdr_log_psnr"] == "inf"
    # more samples per pixel: closer to the reference in every metric
    assert float(low["psnr"]) < float(rows["default"]["psnr"]) < float(high["psnr"]) < math.inf
    assert float(low["ssim"]) < float(high["ssim"]) < 1.0
    assert float(low["hdr_rel_mse"]) > float(high["hdr_rel_mse"]) > 0.0
    if flip.available():
        assert float(low["flip"]) > float(high["flip"]) > 0.0
        assert float(low["hdr_flip"]) > float(high["hdr_flip"]) > 0.0
    for r in rows.values():
        assert float(r["ms.zoneplate"]) > 0 and float(r["ms.tonemap"]) > 0 and float(r["total_ms"]) > 0
        assert (out / r["image"]).is_file()
    assert (out / "pareto_aa.samples.png").is_file()
    for label in ("aa.samples=1", "aa.samples=4"):
        assert (out / "errors" / f"{label}_absdiff.png").is_file()
    assert not (out / "errors" / "default_absdiff.png").exists()
    md = (out / "sweep.md").read_text()
    assert "| aa.samples=4 |" in md and "pareto_aa.samples.png" in md


def test_surgery_sweep_runs_clean(tmp_path, capsys):
    out = tmp_path / "surgery"
    rc = _sweep(["surgery", "--size", "64x64", "--frames", "2", "--knob", "hbao.directions=2,16",
                 "-p", "shadow.size=256", "--validate", "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 0, err
    rows = _rows(out)
    assert list(rows) == ["reference", "default", "hbao.directions=2", "hbao.directions=16"]
    assert rows["hbao.directions=16"]["param.hbao.directions"] == "16"
    assert {"ms.shadow", "ms.hbao", "ms.tonemap"} <= set(rows["reference"])
    assert all(r["messages"] == "0" and r["psnr"] for r in rows.values())
    assert "3 renderings" in err  # reference and default are one rendering


def test_bad_input_is_a_located_error(tmp_path, capsys):
    rc = _sweep(["surgery", "--knob", "hbao.directons=2", "-o", str(tmp_path / "x")])
    assert rc == 2
    assert "<command line>:1:1: error: unknown param 'hbao.directons'; did you mean 'hbao.directions'" \
        in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
    rc = _sweep(["surgery", "--knob", "hbao.directions=2", "--frames", "0", "-o", str(tmp_path / "x")])
    assert rc == 2 and "--frames must be at least 1" in capsys.readouterr().err
