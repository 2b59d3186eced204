"""benchmarks/frame_ops.py on lavapipe: the render thread's per-frame counts. With the
defaults the lighting test's frame is one command buffer in one VkSubmitInfo2 and its loop
runs fewer bytecodes than the path before session 11 (``RGRAPH_BATCH_CUTS=plan``: two of
each; ``RGRAPH_FRAME_UPDATE=method``: the scene's update method per frame)."""

from __future__ import annotations

import re

import pytest


def _counts(capsys) -> tuple[int, int, int]:
    from benchmarks.frame_ops import main

    assert main(["--tests", "lighting", "--views", "1", "--size", "32x18", "--frames", "6"]) == 0
    line = capsys.readouterr().out.splitlines()[0]
    ops = int(re.search(r"(\d+) bytecodes per frame", line).group(1))
    infos = int(re.search(r"VkSubmitInfo2 (\d+)", line).group(1))
    buffers = int(re.search(r"command_buffers (\d+)", line).group(1))
    return ops, infos, buffers


@pytest.mark.vulkan
def test_frame_ops_counts_the_new_and_the_old_path(capsys, monkeypatch):
    new_ops, new_infos, new_buffers = _counts(capsys)
    monkeypatch.setenv("RGRAPH_BATCH_CUTS", "plan")
    monkeypatch.setenv("RGRAPH_FRAME_UPDATE", "method")
    old_ops, old_infos, old_buffers = _counts(capsys)
    assert (new_infos, new_buffers) == (1, 1)
    assert (old_infos, old_buffers) == (2, 2)
    assert new_ops < old_ops
