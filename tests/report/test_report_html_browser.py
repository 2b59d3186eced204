"""The HTML report in a real browser: headless Chromium renders the page of a plan with real
timings (a lavapipe run) to a PNG; the screenshot must show the charts, not a blank page."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

RGRAPH = [sys.executable, "-m", "rgraph"]
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def screenshot(page: Path, png: Path, size: tuple[int, int]) -> None:
    run = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--no-first-run",
         f"--user-data-dir={png.parent / 'profile'}", f"--window-size={size[0]},{size[1]}",
         f"--screenshot={png}", page.as_uri()],
        capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and png.is_file(), run.stderr[-2000:]


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (scripts/setup.sh installs it)")
@pytest.mark.skipif(shutil.which("dot") is None, reason="graphviz is not installed")
def test_report_renders_in_chromium(tmp_path):
    from PIL import Image

    timings, page, png = tmp_path / "t.json", tmp_path / "report.html", tmp_path / "report.png"
    run = subprocess.run([*RGRAPH, "run", "surgery", "--size", "32x32", "--timings", str(timings)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    run = subprocess.run([*RGRAPH, "inspect", "surgery", "--size", "32x32", "--timings", str(timings),
                          "--html", str(page)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    text = page.read_text()
    assert "measured on" in text and "ms measured" in text  # bars from the real timings
    screenshot(page, png, (1280, 4000))
    image = np.asarray(Image.open(png).convert("RGB")).astype(np.int16)
    assert image.shape == (4000, 1280, 3)
    non_white = float((image.sum(axis=2) < 720).mean())
    assert non_white > 0.08, f"page looks blank ({non_white:.1%} non-white)"
    colours = np.unique(image[::4, ::4].reshape(-1, 3), axis=0)
    assert len(colours) > 200, "too few colours for charts and a graph"

    def near(rgb: tuple[int, int, int]) -> int:
        return int((np.abs(image - np.array(rgb)).max(axis=2) < 30).sum())

    assert near((0x4E, 0x79, 0xA7)) > 2000, "no graphics-queue bars"   # graphics lane (blended with 0.88 opacity)
    assert near((0xF2, 0x8E, 0x2B)) > 200, "no compute-queue bars"
    assert near((0xDB, 0xE8, 0xF7)) > 2000, "no pass graph nodes"       # graphviz node fill
