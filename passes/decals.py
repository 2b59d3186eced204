"""Box-projected deferred decals: ``decals`` (raster, one full-screen triangle for all decals).

Reads ``normal_sss`` and ``depth`` (sampled), blends into ``diffuse`` and ``specular``
(``color_attachment_blend``, premultiplied-alpha "over"); never writes normals. Decal boxes,
colours, the inverse view-projection and the sun/ambient terms come from the scene's set 0
(``shaders/scene/scene.glsl``: ``Frame``, ``Decals``). What it computes: ``passes/decals_ref.py``.
"""

from __future__ import annotations

from rgraph.impl import PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding


def _locations(setup) -> dict[str, int]:
    colors = [a["resource"] for a in setup.plan_pass["accesses"] if a["usage"].startswith("color_attachment")]
    if sorted(colors) != ["diffuse", "specular"]:
        raise ExecutionError(f"pass {setup.name!r}: decals blend into diffuse and specular, the plan has {colors}")
    return {name: colors.index(name) for name in colors}


@register("decals")
class Decals(PassImpl):
    """See the module docstring."""

    def __init__(self, setup):
        super().__init__(setup)
        self.scene = setup.scene
        loc = _locations(setup)
        self.sets = setup.descriptors([Binding(0, "sampled", "depth", sampler="nearest"),
                                       Binding(1, "sampled", "normal_sss", sampler="nearest")])
        blend = ["premultiplied", "premultiplied"]
        self.pipeline = setup.graphics_pipeline(
            "lib/fullscreen.vert", "decals/decals.frag", [self.scene.set_layout, self.sets.layout],
            defines={"LOC_DIFFUSE": loc["diffuse"], "LOC_SPECULAR": loc["specular"]}, blend=blend)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.draw(3)
