"""``impl: accel_build``: build (or refit) the scene's acceleration structures: a BLAS per
mesh and a TLAS over every instance, camera-relative (``rgraph.vk.rt_scene``), into the plan's
accel buffer with the plan's scratch (``rgraph.vk.accel``). Before each frame's submits it has
the frame's deformed geometry written (``AccelSet.update``: scenes with deformable meshes)."""

from __future__ import annotations

from typing import Any

from rgraph.impl import PassImpl, register


@register("accel_build")
class AccelBuild(PassImpl):
    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        self.builds = [a["resource"] for a in setup.plan_pass["accesses"] if a["usage"] == "accel_build"]

    def update(self, frame: int, frame_set: int) -> None:
        self.setup.accels.update(frame, frame_set)

    def record(self, rec: Any, frame_set: int) -> None:
        for name in self.builds:
            rec.build_accel(self.setup.accels, name, frame_set)
