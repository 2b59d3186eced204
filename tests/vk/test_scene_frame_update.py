"""The frame loop's per-run update (``SceneFrames.frame_update``: a closure with the per-frame
lookups hoisted, issue 18 session 11) writes exactly what ``SceneFrames.update`` writes, on
lavapipe: the Frame uniform, the SkinFrame uniform (alpha, both slots' first entries), the sets'
ring slots in use, the ticks taken and the alpha range, for alphas before, inside and past the
tick period (and a NaN clock), before and after the camera moves, on both frame sets."""

from __future__ import annotations

import pytest
from locations import ROOT
from skinning_helpers import SCENE, SIZE

from rgraph.scene.camera import camera_state
from rgraph.vk.runtime.logic import LogicState

HZ = 60.0
SCENE_GRAPH = ROOT / "graphs" / "clustered.yaml"


def _snapshot(scene) -> tuple:
    from rgraph.scene import packing
    from rgraph.vk.skin_gpu import SKIN_FRAME_BYTES

    return (tuple(b.read(packing.FRAME_BYTES) for b in scene.frame_buffers),
            tuple(b.read(SKIN_FRAME_BYTES) for b in scene.skin.frames),
            tuple(scene.skin.in_use), tuple(scene.ticks_taken), tuple(scene.alpha_range))


def _scramble(scene) -> None:
    from rgraph.scene import packing
    from rgraph.vk.skin_gpu import SKIN_FRAME_BYTES

    for b in scene.frame_buffers:
        b.write(bytes([0xA5]) * packing.FRAME_BYTES)
    for b in scene.skin.frames:
        b.write(bytes([0x5A]) * SKIN_FRAME_BYTES)
    scene.frames.forget_camera()


@pytest.mark.vulkan
def test_frame_update_writes_what_update_writes(tmp_path, monkeypatch):
    import rgraph
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.scene_frame import SceneFrames

    path = tmp_path / "skin_case.yaml"
    path.write_text(SCENE.replace("BONES", "16"))
    plan = compile_graph(SCENE_GRAPH, scene_path=path, size=SIZE,
                         params={"clusters.tile": "16", "clusters.slices": "4", "skin.worker": "thread"})
    with rgraph.open_device(validate=False, verbose=False) as gpu:
        with gpu.load(plan, logic_hz=HZ) as exe:
            scene = exe.executor.scene_gpu
            logic = exe.executor.logic
            assert scene.skin.active
            data = scene.data
            original = data.camera(0)
            moved = camera_state(original.position + 0.5, original.position + [3.0, -1.0, -6.0], [0.0, 1.0, 0.0],
                                 original.fov_y_deg, original.near, original.aspect)
            now = [0.0]
            logic.clock = lambda: now[0]
            fast = scene.frame_update()
            assert getattr(fast, "__func__", None) is not SceneFrames.update
            cases = 0
            for frame in range(8):
                if frame == 4:
                    data.camera = lambda f=0: moved if f >= 4 else original
                tick = 10 + frame
                published = 5.0 + frame / HZ
                logic._states = (LogicState(tick - 1, (tick - 1) / HZ, published - 1 / HZ, (None, frame % 3)),
                                 LogicState(tick, tick / HZ, published, (None, 3 + frame % 2)))
                for offset in (-0.004, 0.0, 0.3 / HZ, 0.999 / HZ, 1.2 / HZ, 2.0 / HZ, float("nan")):
                    now[0] = published + offset
                    s = frame % 2
                    _scramble(scene)
                    scene.alpha_range[:] = [1.0, 0.0]
                    scene.frames.update(frame, s)
                    want = _snapshot(scene)
                    _scramble(scene)
                    scene.alpha_range[:] = [1.0, 0.0]
                    fast(frame, s)
                    assert _snapshot(scene) == want, (frame, offset)
                    cases += 1
            assert cases == 56
            monkeypatch.setenv("RGRAPH_FRAME_UPDATE", "method")  # the A/B switch: the method itself
            assert scene.frame_update() == scene.frames.update
