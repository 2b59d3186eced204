"""``composite``: hdr = diffuse + specular (full-screen raster). Reference: ``composite_ref``."""

from __future__ import annotations

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding


@register("composite")
class Composite(PassImpl):
    """Reads ``diffuse`` and ``specular`` (sampled), writes ``hdr`` (colour attachment)."""

    attachment_load = {"hdr": "dont_care"}  # every pixel is written

    def __init__(self, setup):
        super().__init__(setup)
        self.sets = setup.descriptors([Binding(0, "sampled", "diffuse", sampler="nearest"),
                                       Binding(1, "sampled", "specular", sampler="nearest")])
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", "post/composite.frag", [self.sets.layout])

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3)
