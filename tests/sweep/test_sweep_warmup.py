"""A sweep's warm-up is a frame count (``--warmup`` seconds x 200), the same for every setting,
through ``Executable.warm_up(frames=N)``: a plan that carries no state between frames (surgery)
then renders its content from frame 0 again, so its image is the one without any warm-up; one
that carries state still runs the same number of frames for every setting, whatever each
setting's speed (a wall-time warm-up made a GPU sweep's images depend on it)."""

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
def test_warm_up_runs_exactly_the_frames_asked():
    from rgraph.api import open_device
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.errors import VulkanUnavailable

    try:
        gpu = open_device(validate=True, verbose=False)
    except VulkanUnavailable as exc:  # pragma: no cover - environment without Vulkan
        pytest.skip(str(exc))
    with gpu:
        exe = gpu.load(compile_graph("surgery", size=(16, 16), memory=gpu.memory_requirements()))
        assert exe.warm_up(5.0, frames=7) == 7  # the count, not the 5 s
        assert exe.executor.frames_done == 7 and exe.content_frames == 0  # stateless: content from frame 0
        assert exe.warm_up(5.0, frames=0) == 0 and exe.executor.frames_done == 7
        assert exe.close() == []


@pytest.mark.vulkan
def test_the_image_does_not_depend_on_the_warm_up(tmp_path, capsys):
    def image(warmup: str, name: str) -> bytes:
        out = tmp_path / name
        assert sweep(["surgery", "--size", "32x32", "--frames", "1", "--knob", "sss.samples=17", "--warmup", warmup,
                      "--validate", "--no-progress", "-o", str(out)]) == 0, capsys.readouterr().err
        assert "0 validation message(s)" in capsys.readouterr().err
        return (out / "images" / "reference.png").read_bytes()

    none = image("0", "a")
    assert image("0.05", "b") == none and image("0.01", "c") == none  # 10 and 2 warm-up frames
