"""``tonemap_filmic``: Hable filmic curve, hdr -> sRGB colour (full-screen raster).

Params: ``tonemap.exposure`` (2.0), ``tonemap.white`` (11.2). Reference and hard-input rules:
``tonemap_ref``.
"""

from __future__ import annotations

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, pack

from .stereo import view_layers
from .tonemap_ref import X_CAP, hable


@register("tonemap_filmic")
class TonemapFilmic(PassImpl):
    """Reads ``hdr`` (sampled), writes ``color`` (an sRGB attachment encodes the linear result)."""
    param_schema = {"tonemap.exposure": Param(float, 0, 1e6), "tonemap.white": Param(float, 1e-6, 1e6)}

    attachment_load = {"color": "dont_care"}  # every pixel is written
    # views=2: hdr and color have a layer per eye; both are drawn in this one render pass as a
    # layered framebuffer, one full-screen instance per layer (gl_Layer). Not VK_KHR_multiview:
    # lavapipe (Mesa, LLVM 15) crashes executing a multiview render pass with only this colour
    # attachment, even with no draw in it.

    def __init__(self, setup):
        super().__init__(setup)
        self.exposure = float(setup.param("tonemap.exposure", 2.0))
        white = float(setup.param("tonemap.white", 11.2))
        if not white > 0:
            raise ExecutionError(f"pass {setup.name!r}: tonemap.white must be > 0, got {white}")
        self.inv_white_mapped = float(1.0 / hable(min(white, X_CAP)))
        self.layers = view_layers(setup)
        stereo = self.layers > 1
        self.sets = setup.descriptors([Binding(0, "sampled", "hdr", sampler="nearest", array=stereo)])
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", "post/tonemap_filmic.frag", [self.sets.layout],
                                                push_constant_bytes=8, defines={"FULLSCREEN_LAYERS": self.layers})

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, pack("2f", self.exposure, self.inv_white_mapped))
        rec.draw(3, self.layers)
