"""Two small implementations exercising the impl API end to end."""

from __future__ import annotations

from pathlib import Path

from rgraph.impl import PassImpl, register
from rgraph.vk.passkit import Binding, pack

SHADERS = Path(__file__).parent


@register("test_scale")
class Scale(PassImpl):
    """dst = src * params.scale.gain (compute, storage image write)."""

    def __init__(self, setup):
        super().__init__(setup)
        self.gain = float(setup.param("scale.gain", 2.0))
        self.sets = setup.descriptors([Binding(0, "sampled", "src", sampler="nearest"),
                                       Binding(1, "storage_image", "scaled")])
        self.pipeline = setup.compute_pipeline(str(SHADERS / "scale.comp"), [self.sets.layout],
                                               push_constant_bytes=4)
        self.extent = setup.extent_of("scaled")

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, pack("f", self.gain))
        rec.dispatch(-(-self.extent[0] // 8), -(-self.extent[1] // 8))


@register("test_blit")
class Blit(PassImpl):
    """A full-screen triangle copying ``src`` into the colour attachment, plus a per-frame tint
    from host-visible memory updated every frame (uniform buffer per frame-in-flight set)."""

    clear_values = {"out": (0.25, 0.5, 0.75, 1.0)}

    def __init__(self, setup):
        super().__init__(setup)
        self.uniforms = [setup.host_buffer(16) for _ in range(setup.sets)]
        self.sets = setup.descriptors([
            Binding(0, "sampled", "scaled", sampler="nearest"),
            Binding(1, "uniform_buffer", buffers=tuple((u.handle, 16) for u in self.uniforms))])
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", str(SHADERS / "blit.frag"), [self.sets.layout])

    def update(self, frame, frame_set):
        self.uniforms[frame_set].write(pack("4f", 0.0, 0.0, 0.0, float(frame)))

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3)
