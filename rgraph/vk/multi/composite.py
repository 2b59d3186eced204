"""Sort-last composite (``rgraph.multi.depth_composite``): device ``d``'s colour + depth drawn
over device 0's with the depth test (reversed-Z, GREATER: strictly nearer wins, ties keep
device 0), as one full-screen triangle. Colour attachments load device 0's values. Layered
attachments (``views=2``) are composited layer by layer: one multiview pass, each view
sampling its layer of the remote images."""

from __future__ import annotations

from typing import Any

from rgraph.formats import lookup
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
        defines: dict[str, Any] = {"COLORS": len(colors), "LAYERED": int(layered)}
        for i, color in enumerate(colors):  # sampler and output of the colour's numeric type
            prefix = numeric_prefix(setup.resource_plan(color)["format"])
            defines[f"SAMPLER{i}"] = f"{prefix}sampler2D{'Array' if layered else ''}"
            defines[f"OUT{i}"] = f"{prefix}vec4"
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", "multi/depth_composite.frag",
                                                [self.sets.layout], defines=defines,
                                                depth_test=True, depth_write=True, depth_compare="GREATER")

    def record(self, rec: Any, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3)


def numeric_prefix(format_name: str) -> str:
    """The GLSL type prefix of a colour format's numeric type: ``u`` (UINT), ``i`` (SINT) or ``""``."""
    numeric = lookup(format_name).numeric
    return {"UINT": "u", "SINT": "i"}.get(numeric, "")
