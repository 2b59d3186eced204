"""Box-projected deferred decals: ``decals`` (raster, one full-screen triangle for all decals).

Reads ``normal_sss`` and ``depth`` (sampled), blends into ``diffuse`` and ``specular``
(``color_attachment_blend``, premultiplied-alpha "over"); never writes normals. Decal boxes,
colours, the inverse view-projection and the sun/ambient terms come from the scene's set 0
(``shaders/scene/scene.glsl``: ``Frame``, ``Decals``). What it computes: ``passes/decals_ref.py``.

Stereo (graph param ``views`` = 2, issue 18): ``depth``, ``normal_sss``, ``diffuse`` and
``specular`` have a layer per eye. A full-screen pass, so not VK_KHR_multiview (lavapipe crashes
executing a multiview render pass with colour attachments only; passes/tonemap.py): one layered
framebuffer, one full-screen instance per layer (``FULLSCREEN_LAYERS``, ``gl_Layer``), the inputs
bound as 2D-array views and read at the fragment's layer; each eye reconstructs positions with
its own inverse view-projection (the centre camera's, moved by the Views uniform's eye offset).
With ``views`` = 1 nothing changes.
"""

from __future__ import annotations

from rgraph.impl import PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding

from .stereo import view_layers


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
        self.layers = view_layers(setup)
        stereo = self.layers > 1
        self.sets = setup.descriptors([Binding(0, "sampled", "depth", sampler="nearest", array=stereo),
                                       Binding(1, "sampled", "normal_sss", sampler="nearest", array=stereo)])
        blend = ["premultiplied", "premultiplied"]
        defines = {"LOC_DIFFUSE": loc["diffuse"], "LOC_SPECULAR": loc["specular"]}
        if stereo:
            defines["FULLSCREEN_LAYERS"] = self.layers
        self.pipeline = setup.graphics_pipeline(
            "lib/fullscreen.vert", "decals/decals.frag", [self.scene.set_layout, self.sets.layout],
            defines=defines, blend=blend)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.draw(3, self.layers)
