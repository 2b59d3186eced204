"""Sort-last composite (``rgraph.multi.depth_composite``): device ``d``'s colour + depth drawn
over device 0's with the depth test (reversed-Z, GREATER: strictly nearer wins, ties keep
device 0), as one full-screen triangle. Colour attachments load device 0's values. Layered
attachments (``views=2``) are composited layer by layer: one multiview pass, each view
sampling its layer of the remote images."""

from __future__ import annotations

from typing import Any

from rgraph.impl import PassImpl, register
from rgraph.plan.devices import COMPOSITE_IMPL
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding

MAX_COLORS = 4


@register(COMPOSITE_IMPL)
class DepthComposite(PassImpl):
    multiview = "layers"

    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        depth = str(setup.param("depth"))
        accesses = setup.plan_pass["accesses"]
        remote = {a["resource"].rsplit(".remote", 1)[0]: a["resource"] for a in accesses if a["usage"] == "sampled"}
        colors = [a["resource"] for a in accesses if a["usage"].startswith("color_attachment")]
        if len(colors) > MAX_COLORS:
            raise ExecutionError(f"pass {setup.name!r}: the composite takes at most {MAX_COLORS} colour attachments")
        layered = setup.layers > 1
        bindings = [Binding(0, "sampled", remote[depth], sampler="nearest", array=layered)]
        bindings += [Binding(1 + i, "sampled", remote[c], sampler="nearest", array=layered)
                     for i, c in enumerate(colors)]
        self.sets = setup.descriptors(bindings)
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", "multi/depth_composite.frag",
                                                [self.sets.layout],
                                                defines={"COLORS": len(colors), "LAYERED": int(layered)},
                                                depth_test=True, depth_write=True, depth_compare="GREATER")

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3)
