"""rgraph.vk.scene_frame on lavapipe: the render thread's fast path (only the Frame uniform's
time words while the set shows the same camera) leaves exactly the bytes the full write
(``packing.frame_bytes``) would, for every frame and set, before and after the camera moves,
mono and stereo (the Views uniform follows the camera)."""

from __future__ import annotations

import pytest
from locations import ROOT

from rgraph.scene import instances as scene_instances
from rgraph.scene import packing
from rgraph.scene.camera import camera_state

SCENE = ROOT / "graphs" / "scenes" / "lighting_test.yaml"


@pytest.mark.vulkan
@pytest.mark.parametrize("views", [1, 2])
def test_fast_frame_writes_equal_full_writes(views):
    import rgraph
    from rgraph.compiler.pipeline import compile_graph

    plan = compile_graph(ROOT / "graphs" / "clustered.yaml", scene_path=SCENE, size=(32, 18),
                         params={"views": str(views)})
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        with gpu.load(plan) as exe:
            scene = exe.executor.scene_gpu
            data = scene.data
            original = data.camera(0)
            moved = camera_state(original.position + 0.5, original.position + [3.0, -1.0, -6.0], [0.0, 1.0, 0.0],
                                 original.fov_y_deg, original.near, original.aspect)

            def check(frame: int) -> None:
                s = frame % 2
                want = packing.frame_bytes(data, frame, data.seconds(frame))
                assert scene.frame_buffers[s].read(packing.FRAME_BYTES) == want, f"frame {frame}"
                if views > 1:
                    size = scene_instances.views_size(views)
                    assert scene.view_buffers[s].read(size) == scene_instances.views_bytes(data, frame, views, scene.ipd)

            for frame in range(6):
                scene.update(frame, frame % 2)
                check(frame)
            data.camera = lambda frame=0: moved if frame >= 6 else original
            for frame in range(6, 10):
                scene.update(frame, frame % 2)
                check(frame)
        messages = gpu.close()
    assert [m.text for m in messages] == []
