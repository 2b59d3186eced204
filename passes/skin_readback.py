"""``skin_readback`` (compute): the posed vertices of the scene's first skinned mesh, every
instance, through ``shaders/scene/skinning.glsl`` (the vertex shaders' code) into a graph
buffer, so that tests compare the GPU's skinning with the NumPy reference.

Writes ``skinned`` (a storage buffer of at least ``2 * instances * vertices * 16`` bytes):
positions ``(x, y, z, 1)`` at ``instance * vertices + v``, then the normals (unnormalised, w 0).
Param ``skin_readback.alpha``: the interpolation factor (-1, default: the frame's).
"""

from __future__ import annotations

from rgraph.impl import Param, PassImpl, register
from rgraph.scene import packing
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, pack

VEC4 = 16


@register("skin_readback")
class SkinReadback(PassImpl):
    """See the module docstring."""

    param_schema = {"skin_readback.alpha": Param(float, -1.0, 1.0)}

    def __init__(self, setup) -> None:
        super().__init__(setup)
        self.scene = setup.scene
        meshes = self.scene.skin.meshes if self.scene.skin is not None else []
        if not meshes:
            raise ExecutionError(f"pass {setup.name!r}: the scene has no skinned mesh")
        mesh, first_vertex = meshes[0]
        self.groups = (-(-mesh.data.vertex_count // 64), mesh.instances)
        need = 2 * mesh.instances * mesh.data.vertex_count * VEC4
        if setup.buffer("skinned", 0)[1] < need:
            raise ExecutionError(f"pass {setup.name!r}: buffer 'skinned' needs at least {need} bytes")
        rest = packing.vertex_bytes(mesh.data)
        rest_buffer = setup.host_buffer(len(rest), "storage")
        rest_buffer.write(rest)
        alpha = float(setup.param("skin_readback.alpha", -1.0))
        self.push = pack("4If", first_vertex, mesh.data.vertex_count, mesh.first_draw, mesh.instances, alpha)
        self.sets = setup.descriptors([Binding(0, "storage_buffer", "skinned"),
                                       Binding(1, "storage_buffer", buffers=((rest_buffer.handle, len(rest)),))])
        self.pipeline = setup.compute_pipeline("scene/skin_readback.comp", [self.scene.set_layout, self.sets.layout],
                                               push_constant_bytes=20)

    def record(self, rec, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups)
