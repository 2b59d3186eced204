"""draw.mode=naive (``--naive-cpu``) with frames in flight, on lavapipe under validation +
synchronization validation (issue 18 d).

The camera moves every frame (three cameras in turn, so the two frame-in-flight sets see
every camera): each of the last two frames, read back from its own set, equals a fresh run
of a scene authored with that frame's camera, within one 8-bit code - a frame never draws
another frame's CPU-culled commands or matrices. The host-written tables are copied to
per-set device buffers in the frame's command buffers (``rgraph.vk.scene_naive``); zero
validation messages.
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
def test_naive_frames_in_flight_draw_their_own_camera(tmp_path):
    import rgraph
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.runtime.readback import decode_outputs

    paths = [scene_file(tmp_path, LIGHTS, camera=_moved_camera(np.array(o)), meshes=MESHES, name=f"cam{k}")
             for k, o in enumerate(OFFSETS)]
    cameras = [load_scene_data(p, SIZE).camera(0) for p in paths]
    want = [srgb_codes(render(p, size=SIZE, params={"draw.mode": "naive"})[1]) for p in paths]
    assert min(np.abs(want[a] - want[b]).max() for a, b in ((0, 1), (1, 2), (0, 2))) > 20  # the cameras differ
    plan = compile_graph(GRAPH, scene_path=paths[0], size=SIZE, params=PARAMS)
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        with gpu.load(plan) as exe:
            scene = exe.executor.scene_gpu
            assert scene.naive is not None and len({b.handle for b in scene.naive.commands}) == 2  # one per set
            scene.data.camera = lambda frame=0: cameras[frame % len(cameras)]
            exe.run(7)  # frames 0..6: 5 is in set 1 (camera 2), 6 in set 0 (camera 0)
            for frame in (5, 6):
                got = srgb_codes(decode_outputs(plan, exe.executor.read_back(frame + 1)))
                diff = np.abs(got - want[frame % len(cameras)])
                assert diff.max() <= 1, f"frame {frame}: max diff {diff.max()} codes"
        messages = gpu.close()
    assert [m.text for m in messages] == []
