"""Batched submission after a multiview pass (lavapipe writes one timestamp per view of the
last render pass even outside it; ``rgraph.vk.runtime.setup.QUERY_SLACK``). A validated run
submits each pass alone, so only a run without the layer records the batch that crashed."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.vulkan


def _run(args: list[str]) -> subprocess.CompletedProcess:
    code = f"import sys; from rgraph.cli import main; sys.exit(main({args!r}))"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("split", ["sort-last", "sort-first"])
def test_stereo_split_frames_run_batched(tmp_path: Path, split: str) -> None:
    """Each device's share ends with the multiview forward pass and its downloads in one batch:
    their timestamps spilled past the query pool and the driver crashed (SIGSEGV)."""
    out = _run(["run", "clustered", "-p", "views=2", "--devices", "0,0", "--split", split, "--size", "32x24",
                "--frames", "2", "--out", str(tmp_path / "stereo.png")])
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert (tmp_path / "stereo.png").exists()
