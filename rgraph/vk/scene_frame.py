"""The scene's per-frame host writes (``SceneGPU.update``) and the logic thread's tick.

The render thread's only scene work per frame. What it writes, per frame-in-flight set
(the set's previous frame has finished: its fence was waited):

- the Frame uniform: in full (``packing.frame_bytes``) when the set last showed another
  camera (a ``CameraState`` object: ``SceneData.camera`` returns the same one while the camera
  stays), otherwise only its two time words (scene time, frame number), through a NumPy view
  of the mapped memory - no per-frame allocation, no matrix work;
- the camera-relative Draws (draw modes cpu and naive), Decals and Views with the camera;
  draw.mode=naive (the engines' way) writes every object's matrix and draw command every frame;
- without a logic thread: the skinning state and deformable positions of the frame's time
  (the positions written ahead, right after the previous frame's submits: ``prepare``);
- with one (``rgraph run --logic-hz``): only the interpolation headers - the logic thread
  (``logic_step``) writes each tick's deformable positions and packed bones straight into
  free slots of the two host-visible rings; ``update`` takes the last two states and marks
  their slots in use by the set, under ``lock``, in one step.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from typing import Any

from rgraph.scene import instances as scene_instances
from rgraph.scene import packing
from rgraph.vk.loader import vk
from rgraph.vk.runtime.logic import interpolation_alpha

TIME_WORD = packing.FRAME_OFFSETS["time"] // 4  # Frame.time: (seconds, frame, near, fov_y)
INF = float("inf")


def float_words(buffer: Any) -> Any:
    """A cffi ``float *`` over a HostBuffer's mapped memory (valid while it stays mapped)."""
    ffi = vk().ffi
    return ffi.cast("float *", ffi.from_buffer(buffer.mapped))


class SceneFrames:
    """See the module docstring; ``scene`` is the ``SceneGPU`` whose host buffers it writes."""

    def __init__(self, scene: Any) -> None:
        self.scene = scene
        self.frame_words = [float_words(buf) for buf in scene.frame_buffers]  # per set: its Frame uniform
        self.camera_of: list[Any] = [None] * scene.sets  # per set: the CameraState its tables show
        # the logic thread's lock too (LogicThread(lock=...)): ring slots change hands under it
        self.lock = scene.deform.lock if scene.deform is not None else threading.Lock()

    def forget_camera(self) -> None:
        """Every set's camera-dependent tables are written again at its next update."""
        self.camera_of = [None] * self.scene.sets

    # ----------------------------------------------------------------- render thread
    def frame_update(self) -> Callable[[int, int], None]:
        """``update`` for one run of frames (the frame loop takes it once per run): with a
        logic thread and draw modes gpu or cpu, a closure over what ``update`` would look up
        every frame (the scene's parts, the skin's SkinFrame words, the logic's clock), doing
        the same writes in the same order with about half its bytecodes; ``update`` itself
        otherwise, or with ``RGRAPH_FRAME_UPDATE=method``."""
        sc = self.scene
        logic, skin, deform = sc.logic, sc.skin, sc.deform
        if logic is None or sc.mode == "naive" or os.environ.get("RGRAPH_FRAME_UPDATE") == "method":
            return self.update  # RGRAPH_FRAME_UPDATE=method: the path before session 11 (an A/B switch)
        lock, latest, clock, hz = self.lock, logic.latest, logic.clock, logic.hz
        camera, frame_words, camera_tables = sc.data.camera, self.frame_words, self._camera_tables
        alpha_range, ticks_taken = sc.alpha_range, sc.ticks_taken
        skinned = skin.active
        skin_in_use, skin_words = skin.in_use, skin.frame_words
        header, bones = skin.header, skin.bones
        word = TIME_WORD

        def update(frame: int, frame_set: int) -> None:
            with lock:
                prev, cur = latest()
                if deform is not None:
                    deform.in_use[frame_set] = (prev.value[0], cur.value[0])
                if skinned:
                    skin_in_use[frame_set] = (a := prev.value[1], b := cur.value[1])
            alpha = (clock() - cur.wall) * hz  # interpolation_alpha, inlined
            if not 0.0 < alpha < INF:
                alpha = 0.0
            elif alpha > 1.0:
                alpha = 1.0
            seconds = prev.seconds + alpha * (cur.seconds - prev.seconds)
            if alpha < alpha_range[0]:
                alpha_range[0] = alpha
            if alpha > alpha_range[1]:
                alpha_range[1] = alpha
            cam = camera(frame)
            if cam is not self.camera_of[frame_set]:
                camera_tables(frame, frame_set, seconds)
                self.camera_of[frame_set] = cam
            else:
                words = frame_words[frame_set]
                words[word] = seconds
                words[word + 1] = frame
            if skinned:  # SkinGPU.show_slots, inlined (alpha is in [0, 1] already)
                f, u = skin_words[frame_set]
                f[0] = alpha
                u[1] = header + a * bones
                u[2] = header + b * bones
            if deform is not None:
                deform.set_header(frame_set, alpha, prev.value[0], cur.value[0])
            ticks_taken[frame_set] = (prev.tick, cur.tick)

        return update

    def update(self, frame: int, frame_set: int) -> None:
        sc = self.scene
        data, logic, skin, deform = sc.data, sc.logic, sc.skin, sc.deform
        if logic is None:
            seconds = data.seconds(frame)
        else:  # between the logic thread's last two states; their slots are this set's now
            with self.lock:
                prev, cur = logic.latest()
                if deform is not None:
                    deform.in_use[frame_set] = (prev.value[0], cur.value[0])
                if skin.active:
                    skin.in_use[frame_set] = (prev.value[1], cur.value[1])
            alpha = interpolation_alpha(logic.clock(), cur.wall, logic.hz)
            seconds = prev.seconds + alpha * (cur.seconds - prev.seconds)
            if alpha < sc.alpha_range[0]:
                sc.alpha_range[0] = alpha
            if alpha > sc.alpha_range[1]:
                sc.alpha_range[1] = alpha
        cam = data.camera(frame)
        naive = sc.mode == "naive"
        if cam is not self.camera_of[frame_set] or naive:
            self._camera_tables(frame, frame_set, seconds)
            self.camera_of[frame_set] = cam
        else:
            words = self.frame_words[frame_set]  # a cffi float*: two small stores, no NumPy call
            words[TIME_WORD] = seconds
            words[TIME_WORD + 1] = frame
        if naive:
            if sc.naive.direct:  # the draws are recorded per frame (SceneGPU.rerecord): the visible ids
                sc.naive.visible[frame_set] = scene_instances.naive_visible(data, frame, sc.views, sc.ipd)
            else:
                sc.naive_buffers[frame_set].write(
                    scene_instances.naive_commands(data, frame, sc.calls, sc.views, sc.ipd))
        if logic is None:
            if skin.active:
                skin.update(seconds, frame_set)
            if deform is not None:
                deform.write(seconds, frame_set, frame)
            return
        if skin.active:  # the logic thread wrote these states' bones (logic_step)
            skin.show_slots(frame_set, prev.value[1], cur.value[1], alpha)
        if deform is not None:
            deform.set_header(frame_set, alpha, prev.value[0], cur.value[0])
        sc.ticks_taken[frame_set] = (prev.tick, cur.tick)

    def _camera_tables(self, frame: int, frame_set: int, seconds: float) -> None:
        """Everything camera-relative of set ``frame_set``: the whole Frame uniform, Draws
        (cpu, naive), Decals, Views."""
        sc = self.scene
        data = sc.data
        sc.frame_buffers[frame_set].write(packing.frame_bytes(data, frame, seconds))
        if sc.mode != "gpu":
            sc.draw_buffers[frame_set].write(packing.draws_bytes(data, frame))
        if data.decals:
            sc.decal_buffers[frame_set].write(packing.decals_bytes(data, frame))
        if sc.views > 1:
            sc.view_buffers[frame_set].write(scene_instances.cached_views_bytes(data, frame, sc.views, sc.ipd))

    def prepare(self, frame: int) -> None:
        """After frame ``frame - 1``'s submits, without a logic thread: what of content frame
        ``frame`` can be written ahead, while the CPU is warm (the deformable positions:
        ``DeformGPU.prepare``)."""
        sc = self.scene
        if sc.logic is None and sc.deform is not None:
            sc.deform.prepare(frame, sc.data.seconds(frame))

    # ----------------------------------------------------------------- logic thread
    def logic_step(self, seconds: float) -> tuple[int | None, int | None]:
        """One tick at scene time ``seconds``: the deformable positions and the packed bones
        written into free slots of their rings (not a published state's, not a set's in use);
        (deformable slot, bones slot), None for what the scene lacks."""
        sc = self.scene
        logic = sc.logic
        bones = None
        if sc.skin.active:
            bones = sc.skin.write_slot(round(seconds * logic.hz), self.lock,
                                       lambda: [st.value[1] for st in logic.published()])
        deform = None
        if sc.deform is not None:
            deform = sc.deform.write_slot(seconds, lambda: [st.value[0] for st in logic.published()])
        return deform, bones
