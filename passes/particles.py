"""Particles: ``particles_sim`` (compute, made for the compute queue) and ``particles_draw``.

``particles_sim`` integrates every particle of its storage buffer (32 bytes each: position
and age, velocity) in place: ``particles.substeps`` steps (4) of ``particles.dt`` (1/240 s)
through a vortex field with gravity and drag; a particle respawns at a hashed position when
its age (``particles.lifetime``, 2 s) runs out or its state is not a live finite one, so
any initial contents work. ``particles_draw`` adds one point per particle to its blended
colour attachment (orthographic x-y), reading the buffer in the vertex shader; with the graph
param ``views`` > 1 one instance per layer of the layered attachment (the same points in each).
"""

from __future__ import annotations

from rgraph.impl import PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, pack

from .stereo import view_layers

PARTICLE_BYTES = 32


def _buffer(setup, usage: str) -> tuple[str, int]:
    found = [a["resource"] for a in setup.plan_pass["accesses"] if a["usage"] == usage]
    if len(found) != 1:
        raise ExecutionError(f"pass {setup.name!r}: expects exactly one {usage} buffer, has {found or 'none'}")
    count = setup.buffer(found[0], 0)[1] // PARTICLE_BYTES
    if count < 1:
        raise ExecutionError(f"pass {setup.name!r}: buffer {found[0]!r} holds no {PARTICLE_BYTES}-byte particle")
    return found[0], count


@register("particles_sim")
class ParticlesSim(PassImpl):
    def __init__(self, setup):
        super().__init__(setup)
        name, self.count = _buffer(setup, "storage_rw")
        substeps = int(setup.param("particles.substeps", 4))
        dt, lifetime = float(setup.param("particles.dt", 1 / 240)), float(setup.param("particles.lifetime", 2.0))
        if substeps < 1 or not dt > 0 or not lifetime > 0:
            raise ExecutionError(f"pass {setup.name!r}: particles.substeps >= 1, particles.dt > 0 and "
                                 f"particles.lifetime > 0 (got {substeps}, {dt}, {lifetime})")
        self.push = pack("2I2f", self.count, substeps, dt, lifetime)
        self.sets = setup.descriptors([Binding(0, "storage_buffer", name)])
        self.pipeline = setup.compute_pipeline("particles/sim.comp", [self.sets.layout],
                                               push_constant_bytes=len(self.push))

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(-(-self.count // 256), 1, 1)


@register("particles_draw")
class ParticlesDraw(PassImpl):
    def __init__(self, setup):
        super().__init__(setup)
        name, self.count = _buffer(setup, "storage_read")
        self.sets = setup.descriptors([Binding(0, "storage_buffer", name)])
        self.layers = view_layers(setup)
        self.pipeline = setup.graphics_pipeline("particles/draw.vert", "particles/draw.frag", [self.sets.layout],
                                                topology="POINT_LIST", blend=["add"],
                                                defines={"PARTICLE_LAYERS": self.layers} if self.layers > 1 else None)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(self.count, self.layers)
