"""Skinning with the logic thread (``--logic-hz``) on lavapipe under validation +
synchronization validation (issue 18, parts 3 and 4).

The logic thread packs each tick's bones and writes them straight into a free slot of the
host-visible ring (``SkinGPU.write_slot``); the render thread only names the frame's two slots
and alpha (``SkinGPU.show_slots``: 12 bytes). Checked: every bone write after tick 0 ran on
the logic thread (the render thread copies no bone state); each frame set's SkinFrame names
the slots its ticks were written to, and those slots hold exactly the packed states of the
ticks the set took; the GPU's posed vertices of the last frame (``skin_readback``) equal the
float64 reference between those two states at the set's alpha; zero validation messages.
With ``skin.worker=process`` (the default) the states come from the worker process, which
ends when the executable closes; with ``thread`` the logic thread evaluates them.
"""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest
from skinning_helpers import SCENE, SIZE, readback_pose, reference_pose_of_ticks, skin_graph

from rgraph.scene.build import load_scene_data
from rgraph.scene.skinning import BONE_BYTES
from rgraph.vk.skin_gpu import SkinGPU

HZ = 240.0


@pytest.mark.vulkan
@pytest.mark.parametrize("worker", ["process", "thread"])
def test_logic_thread_writes_the_bones_and_frames_show_their_own_states(tmp_path, monkeypatch, worker):
    import rgraph
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.vk.runtime.readback import decode_outputs

    writers: list[str] = []
    real_write = SkinGPU._write

    def spy(self, slot, tick):
        writers.append(threading.current_thread().name)
        return real_write(self, slot, tick)

    monkeypatch.setattr(SkinGPU, "_write", spy)
    scene_path = tmp_path / "skin_case.yaml"
    scene_path.write_text(SCENE.replace("BONES", "64"))
    mesh = load_scene_data(scene_path, SIZE).skinned[0]
    plan = compile_graph(skin_graph(tmp_path, 2 * mesh.instances * mesh.data.vertex_count * 16), scene_path=scene_path,
                         size=SIZE, params={"clusters.tile": "16", "clusters.slices": "4", "skin.worker": worker})
    with rgraph.open_device(validate=True, verbose=False) as gpu:
        with gpu.load(plan, logic_hz=HZ) as exe:
            writers.clear()  # construction wrote nothing per tick; from here on: the run
            timings = exe.run(8).timings
            ex = exe.executor
            scene, skin = ex.scene_gpu, ex.scene_gpu.skin
            stats = timings["logic"]["skin"]
            assert stats["worker"] == worker
            if worker == "process":
                pid = skin.worker.pid
                assert pid != os.getpid() and skin.worker.alive
                assert stats["ticks"] >= ex.logic.ticks  # every state written came from the worker
            else:
                assert skin.worker is None
            assert ex.logic.ticks >= 2 and len(writers) == ex.logic.ticks
            assert writers[0] == threading.main_thread().name  # tick 0: LogicThread.start, before frame 0
            assert set(writers[1:]) <= {"rgraph-logic"}  # never the render thread after that
            entries = skin.bones * BONE_BYTES
            for s in range(2):
                a, b = skin.in_use[s]
                prev, cur = scene.ticks_taken[s]
                f, u = skin.frame_words[s]
                assert (u[1], u[2]) == (skin.header + a * skin.bones, skin.header + b * skin.bones)
                for slot, tick in ((a, prev), (b, cur)):
                    start = (skin.header + slot * skin.bones) * BONE_BYTES
                    held = bytes(skin.ring.mapped[start:start + entries])
                    assert held == np.ascontiguousarray(mesh.animator.state(tick, HZ)).tobytes(), (s, slot, tick)
            last = (ex.frames_done - 1) % 2
            alpha = float(skin.frame_words[last][0][0])
            prev, cur = scene.ticks_taken[last]
            outputs = decode_outputs(plan, ex.read_back())
        messages = gpu.close()
    assert [m.text for m in messages] == []
    if worker == "process":  # closed with the executable
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)
    assert 0.0 <= alpha <= 1.0
    got_p, _got_n = readback_pose(mesh, outputs)
    want_p, _want_n = reference_pose_of_ticks(mesh, prev, cur, alpha, HZ)
    assert np.abs(got_p - want_p).max() < 2e-5


@pytest.mark.vulkan
def test_an_unknown_skin_worker_is_a_one_line_error(tmp_path):
    from skinning_helpers import run_skinned

    from rgraph.vk.errors import ExecutionError

    with pytest.raises(ExecutionError, match="skin.worker must be one of process, thread, not 'fork'") as info:
        run_skinned(tmp_path, bones=8, params={"skin.worker": "fork"}, readback=False)
    assert "\n" not in str(info.value)
