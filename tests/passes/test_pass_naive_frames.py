"""draw.mode=naive (``--naive-cpu``) with frames in flight, on lavapipe under validation +
synchronization validation (issue 18 d).

The camera moves every frame (three cameras in turn, so the two frame-in-flight sets see
every camera): each of the last two frames, read back from its own set, equals a fresh run
of a scene authored with that frame's camera, within one 8-bit code - a frame never draws
another frame's CPU-culled commands or matrices. The host-written tables are copied to
per-set device buffers in the frame's command buffers (``rgraph.vk.scene_naive``); zero
validation messages. Both ways of drawing (``draw.naive``): ``direct`` records the frame's
draws of the CPU-visible objects per frame (no indirect draw: the H200 lost the device with
32,768 indirect draws per pass), ``indirect`` reads per-set command tables.
"""

from __future__ import annotations

import numpy as np
import pytest
from clustered_helpers import GRAPH, render, scene_file, srgb_codes
from test_pass_vr_draw import LIGHTS, MESHES, SIZE, _moved_camera

from rgraph.scene.build import load_scene_data

PARAMS = {"draw.mode": "naive", "lighting.mode": "clustered", "clusters.tile": "8", "clusters.slices": "12"}
OFFSETS = ([0.0, 0.0, 0.0], [0.9, 0.2, -0.6], [-0.8, 0.3, 0.7])


@pytest.mark.vulkan
@pytest.mark.parametrize("way", ["direct", "indirect"])
def test_naive_frames_in_flight_draw_their_own_camera(tmp_path, monkeypatch, way):
    """``direct`` (default): the frame's command buffers are recorded again per frame with one
    vkCmdDrawIndexed per CPU-visible object (no indirect draw); ``indirect``: recorded once,
    per-set command tables."""
    import rgraph
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.scene.instances import naive_visible
    from rgraph.vk.record_context import RecordContext
    from rgraph.vk.runtime.readback import decode_outputs

    paths = [scene_file(tmp_path, LIGHTS, camera=_moved_camera(np.array(o)), meshes=MESHES, name=f"cam{k}")
             for k, o in enumerate(OFFSETS)]
    cameras = [load_scene_data(p, SIZE).camera(0) for p in paths]
    want = [srgb_codes(render(p, size=SIZE, params={"draw.mode": "naive"})[1]) for p in paths]
    assert min(np.abs(want[a] - want[b]).max() for a, b in ((0, 1), (1, 2), (0, 2))) > 20  # the cameras differ
    plan = compile_graph(GRAPH, scene_path=paths[0], size=SIZE, params={**PARAMS, "draw.naive": way})
    recorded: list[int] = []  # objects drawn per recorded scene draw (direct)
    indirect: list[int] = []
    each, one = RecordContext.draw_indexed_each, RecordContext.draw_indexed_indirect
    monkeypatch.setattr(RecordContext, "draw_indexed_each",
                        lambda self, *a: (recorded.append(len(a[-1])), each(self, *a))[1])
    monkeypatch.setattr(RecordContext, "draw_indexed_indirect", lambda self, *a: (indirect.append(1), one(self, *a))[1])
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        with gpu.load(plan) as exe:
            scene = exe.executor.scene_gpu
            assert scene.naive is not None and scene.naive.direct == (way == "direct")
            if way == "indirect":
                assert len({b.handle for b in scene.naive.commands}) == 2  # one per set
            scene.data.camera = lambda frame=0: cameras[frame % len(cameras)]
            recorded.clear()
            exe.run(7)  # frames 0..6: 5 is in set 1 (camera 2), 6 in set 0 (camera 0)
            if way == "direct":
                assert not indirect
                for frame, s in ((5, 1), (6, 0)):
                    assert scene.naive.visible[s] == naive_visible(scene.data, frame, 1, scene.ipd)
                assert len({tuple(naive_visible(scene.data, f, 1, scene.ipd)) for f in range(3)}) == 3
                # 7 frames x 2 scene passes (depth prepass, forward) recorded again, per frame
                assert len(recorded) >= 14 and sum(recorded) > 0
            else:
                assert not recorded and indirect
            for frame in (5, 6):
                got = srgb_codes(decode_outputs(plan, exe.executor.read_back(frame + 1)))
                diff = np.abs(got - want[frame % len(cameras)])
                assert diff.max() <= 1, f"frame {frame}: max diff {diff.max()} codes"
        messages = gpu.close()
    assert [m.text for m in messages] == []
