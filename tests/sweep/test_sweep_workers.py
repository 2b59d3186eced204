"""``rgraph sweep --workers N`` on lavapipe under validation: the same outputs as the
one-process sweep except measured times; a killed worker is retried; one killed twice is
reported for its setting while the others finish; Ray is never imported."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest
import sweep_helpers
from locations import ROOT, TESTS
from sweep_helpers import ARGS, rows, sweep

from rgraph.sweep.remote import KILL_ENV
from rgraph.sweep.same import differences, timeless_csv, timeless_md

pytestmark = pytest.mark.vulkan
one_process = sweep_helpers.one_process  # the module-scoped one-process sweep (a fixture)


def test_same_sweep_masks_times_only(one_process):
    table = timeless_csv(one_process / "sweep.csv")
    assert table and not any(k.startswith("ms.") or k == "total_ms" for k in table[0])
    assert {"psnr", "ssim", "hdr_rel_mse", "messages", "image"} <= set(table[0])
    md = (one_process / "sweep.md").read_text()
    masked = timeless_md(md)
    total = rows(one_process)["aa.samples=1"]["total_ms"]
    assert total in md and total not in masked  # the measured time is masked...
    psnr = rows(one_process)["aa.samples=1"]["psnr"]
    assert psnr in masked  # ...the error is not


def test_differences_sees_all_but_times(one_process, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(one_process, copy)
    assert differences(one_process, copy) == []
    text = (copy / "sweep.csv").read_text()
    total = rows(one_process)["aa.samples=1"]["total_ms"]
    (copy / "sweep.csv").write_text(text.replace(total, "12345.6"))
    (copy / "sweep.md").write_text((copy / "sweep.md").read_text().replace(total, "12345.6"))
    assert differences(one_process, copy) == []  # a time changed
    (copy / "sweep.csv").write_text(text.replace(rows(one_process)["aa.samples=1"]["ssim"], "0.5"))
    (copy / "images" / "default.png").write_bytes(b"x")
    (copy / "pareto_aa.samples.png").write_bytes(b"x")  # time-placed: only its presence counts
    assert differences(one_process, copy) == ["sweep.csv", "images/default.png"]


def test_workers_give_the_one_process_sweep(one_process, tmp_path, capsys):
    out = tmp_path / "w"
    assert sweep([*ARGS, "--workers", "2", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "in 2 local worker processes" in err and "0 validation message(s)" in err
    assert differences(one_process, out) == []
    assert (out / "errors" / "aa.samples=1_absdiff.png").is_file()


def test_killed_worker_is_retried(one_process, tmp_path, monkeypatch, capsys):
    marker = tmp_path / "killed-once"
    monkeypatch.setenv(KILL_ENV, f"reference@{marker}")
    out = tmp_path / "w"
    assert sweep([*ARGS, "--workers", "2", "-o", str(out)]) == 0, capsys.readouterr().err
    assert marker.is_file()  # its first worker really died
    assert differences(one_process, out) == []


def test_worker_killed_twice_is_reported_for_its_setting(one_process, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(KILL_ENV, "aa.samples=1")
    out = tmp_path / "w"
    assert sweep([*ARGS, "--workers", "3", "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert ("setting aa.samples=1 failed: attempt 1: worker process killed by signal 9; "
            "attempt 2: worker process killed by signal 9") in err
    got, want = rows(out), rows(one_process)
    assert list(got) == list(want)
    assert got["aa.samples=1"]["total_ms"] == got["aa.samples=1"]["psnr"] == got["aa.samples=1"]["image"] == ""
    for label in ("reference", "default", "aa.samples=2"):  # the others finished
        assert got[label]["psnr"] == want[label]["psnr"] and got[label]["image"] == want[label]["image"]
    assert "aa.samples=1: not rendered: attempt 1:" in (out / "sweep.md").read_text()


def test_no_ray_without_ray(tmp_path):
    """A plain sweep and a --workers one import no Ray (Ray is installed here)."""
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import sweep_fixtures.passes; "
            "from rgraph.cli import main; argv = sys.argv[2:]; "
            "assert main(argv) == 0; assert 'ray' not in sys.modules, 'ray imported by a plain sweep'; "
            "assert main([*argv[:-1], argv[-1] + 'w', '--workers', '1']) == 0; "
            "assert 'ray' not in sys.modules, 'ray imported by --workers'")
    argv = ["sweep", ARGS[0], "--size", "16x16", "--frames", "1", "--knob", "aa.samples=1",
            "--no-progress", "-o", str(tmp_path / "o")]
    done = subprocess.run([sys.executable, "-c", code, str(TESTS), *argv], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "ow" / "sweep.csv").is_file()


def test_bad_worker_count_is_a_located_error(tmp_path, capsys):
    assert sweep([*ARGS, "--workers", "0", "-o", str(tmp_path / "x")]) == 2
    assert "<command line>:1:1: error: --workers must be at least 1, got 0" in capsys.readouterr().err


def test_ray_missing_is_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "ray", None)  # as if Ray were not installed
    assert sweep([*ARGS, "--ray", "-o", str(tmp_path / "x")]) == 2
    assert "rgraph: error: --ray needs Ray: pip install 'rgraph[ray]'" in capsys.readouterr().err


def test_workers_started_after_the_reference_compare_with_it(one_process, tmp_path, monkeypatch, capsys):
    """With one worker the reference renders first, so every later job carries its images
    and its worker computes the metrics and draws the error maps: the parent compares only the
    reference with itself and draws no error map (the worker's are the same bytes)."""
    from rgraph.sweep import collect, plots

    real = collect.compare

    def parent_compare(reference, test):
        assert reference is test, "a worker that had the reference should have compared"
        return real(reference, test)

    def parent_draws(*args):
        raise AssertionError("a worker that had the reference should have drawn the error maps")

    monkeypatch.setattr(collect, "compare", parent_compare)
    monkeypatch.setattr(plots, "error_map_pngs", parent_draws)
    out = tmp_path / "w1"
    assert sweep([*ARGS, "--workers", "1", "-o", str(out)]) == 0, capsys.readouterr().err
    assert differences(one_process, out) == []


def test_several_settings_per_worker_give_the_one_process_sweep(one_process, tmp_path, capsys):
    out = tmp_path / "k"
    assert sweep([*ARGS, "--workers", "2", "--per-worker", "4", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "in 2 local worker processes (4 settings each)" in err and "0 validation message(s)" in err
    assert differences(one_process, out) == []


def test_bad_per_worker_is_a_located_error(tmp_path, capsys):
    assert sweep([*ARGS, "--workers", "2", "--per-worker", "0", "-o", str(tmp_path / "x")]) == 2
    assert "<command line>:1:1: error: --per-worker must be at least 1, got 0" in capsys.readouterr().err
