"""The zone-plate graph's two passes (registered on import)."""

from __future__ import annotations

from pathlib import Path

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding, pack

HERE = Path(__file__).parent
GRAPH = HERE / "graph.yaml"


@register("sweep_zoneplate")
class ZonePlate(PassImpl):
    """hdr = intensity * box-filtered zone plate, aa.samples^2 samples per pixel."""

    def __init__(self, setup):
        super().__init__(setup)
        self.samples = int(setup.param("aa.samples", 2))
        self.intensity = float(setup.param("zone.intensity", 4.0))
        self.sets = setup.descriptors([Binding(0, "storage_image", "hdr")])
        self.pipeline = setup.compute_pipeline(str(HERE / "zoneplate.comp"), [self.sets.layout],
                                               push_constant_bytes=8)
        self.extent = setup.extent_of("hdr")

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, pack("if", self.samples, self.intensity))
        rec.dispatch(-(-self.extent[0] // 8), -(-self.extent[1] // 8))


@register("sweep_reinhard")
class Reinhard(PassImpl):
    """color = hdr / (1 + hdr), written to an sRGB attachment."""

    def __init__(self, setup):
        super().__init__(setup)
        self.sets = setup.descriptors([Binding(0, "sampled", "hdr", sampler="nearest")])
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", str(HERE / "reinhard.frag"), [self.sets.layout])

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3)
