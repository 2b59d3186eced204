"""A sweep's warm-up is a frame count, the same for every setting: surgery's scene animates by
frame index, so the image read back depends on how many frames ran before it (a wall-time
warm-up made a GPU sweep's images, and so its errors, depend on each setting's speed)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from sweep_helpers import sweep

from rgraph.sweep.runner import WARMUP_FPS, SweepRequest, warmup_frames


def test_warmup_frames_from_seconds():
    gpu, cpu = SimpleNamespace(default_warmup_s=0.3), SimpleNamespace(default_warmup_s=0.0)
    assert WARMUP_FPS == 200
    assert warmup_frames(SweepRequest("g", []), gpu) == 60
    assert warmup_frames(SweepRequest("g", []), cpu) == 0
    assert warmup_frames(SweepRequest("g", [], warmup_s=0.05), cpu) == 10
    assert warmup_frames(SweepRequest("g", [], warmup_s=0.001), gpu) == 1  # at least one frame
    assert warmup_frames(SweepRequest("g", [], warmup_s=0.0), gpu) == 0


@pytest.mark.vulkan
def test_the_image_depends_on_the_frame_count_only(tmp_path, capsys):
    def image(warmup: str, name: str) -> bytes:
        out = tmp_path / name
        assert sweep(["surgery", "--size", "32x32", "--frames", "1", "--knob", "sss.samples=17", "--warmup", warmup,
                      "--validate", "--no-progress", "-o", str(out)]) == 0, capsys.readouterr().err
        assert "0 validation message(s)" in capsys.readouterr().err
        return (out / "images" / "reference.png").read_bytes()

    ten = image("0.05", "a")
    assert image("0.05", "b") == ten  # 10 warm-up frames twice: the same moment of the animation
    assert image("0.01", "c") != ten  # 2 warm-up frames: another moment
