"""``composite``: hdr = diffuse + specular (full-screen raster). Reference: ``composite_ref``.

Stereo (graph param ``views`` = 2, issue 18): ``diffuse``, ``specular`` and ``hdr`` have a layer
per eye; like passes/tonemap.py one layered framebuffer (not VK_KHR_multiview, which lavapipe
crashes on with colour attachments only), one full-screen instance per layer
(``FULLSCREEN_LAYERS``, ``gl_Layer``), the inputs as 2D-array views read at the fragment's layer.
With ``views`` = 1 nothing changes.
"""

from __future__ import annotations

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding

from .stereo import view_layers


@register("composite")
class Composite(PassImpl):
    """Reads ``diffuse`` and ``specular`` (sampled), writes ``hdr`` (colour attachment)."""

    attachment_load = {"hdr": "dont_care"}  # every pixel is written

    def __init__(self, setup):
        super().__init__(setup)
        self.layers = view_layers(setup)
        stereo = self.layers > 1
        self.sets = setup.descriptors([Binding(0, "sampled", "diffuse", sampler="nearest", array=stereo),
                                       Binding(1, "sampled", "specular", sampler="nearest", array=stereo)])
        defines = {"FULLSCREEN_LAYERS": self.layers} if stereo else None
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", "post/composite.frag", [self.sets.layout],
                                                defines=defines)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3, self.layers)
