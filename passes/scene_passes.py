"""Scene passes: ``light_setup`` (compute), ``shadow_map`` and ``depth_prepass`` (raster).

All three bind the scene (``setup.scene``: ``rgraph.vk.scene_gpu.SceneGPU``) as descriptor
set 0; see ``shaders/scene/scene.glsl`` for the conventions (camera-relative world,
reversed-Z infinite projection, reversed orthographic shadow depth). NumPy references:
``passes/scene_ref.py``.
"""

from __future__ import annotations

from rgraph.impl import Param, PassImpl, register
from rgraph.vk import dispatch
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, pack

from .gpu_draw import draw_args

#: Scene geometry is counter-clockwise seen from outside; with the Y-flipped projection and
#: Vulkan's framebuffer orientation it stays counter-clockwise.
SCENE_FRONT_FACE = "COUNTER_CLOCKWISE"
#: Shadow depth bias (constant, slope) for reversed depth: negative pushes stored depth away
#: from the light.
SHADOW_BIAS = (-2.0, -1.5)


@register("depth_prepass")
class DepthPrepass(PassImpl):
    """Writes ``depth`` (d32_sfloat): reversed-Z (clear 0, GREATER_OR_EQUAL), infinite far plane,
    invariant positions from ``scene_clip_position`` (forward matches them bit for bit).
    Reads ``draw_args`` as ``indirect`` when the graph culls on the GPU (``passes.gpu_draw``).
    Param ``depth_prepass.cull`` (``back`` default, or ``none``)."""
    param_schema = {"depth_prepass.cull": Param(str, choices=("back", "front", "none"))}

    clear_values = {"depth": 0.0}
    attachment_load = {"depth": "clear"}
    multiview = True

    def __init__(self, setup):
        super().__init__(setup)
        self.scene = setup.scene
        cull = str(setup.param("depth_prepass.cull", "back")).upper()
        self.pipeline = setup.graphics_pipeline(
            "scene/depth_prepass.vert", None, [self.scene.set_layout], vertex_input=self.scene.position_input,
            cull=cull, front_face=SCENE_FRONT_FACE, depth_test=True, depth_write=True,
            depth_compare="GREATER_OR_EQUAL")

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set)])
        self.scene.draw(rec, frame_set, self.setup.param("rgraph.draws"), args=draw_args(self.setup, frame_set))


@register("shadow_map")
class ShadowMap(PassImpl):
    """Writes ``shadow_maps`` (d32_sfloat array, one layer per shadow-casting directional light):
    one pipeline for every layer, the layer by push constant and ``gl_Layer`` in the vertex
    shader (Vulkan 1.2 ``shaderOutputLayer``). Reversed orthographic depth (clear 0, 1 nearest
    the light), depth bias ``shadow.bias_constant``/``shadow.bias_slope``."""
    param_schema = {"shadow.bias_constant": Param(float, -1e6, 1e6), "shadow.bias_slope": Param(float, -1e6, 1e6)}

    clear_values = {"shadow_maps": 0.0}
    attachment_load = {"shadow_maps": "clear"}

    def __init__(self, setup):
        super().__init__(setup)
        if "shaderOutputLayer" not in setup.device.enabled_features:
            raise ExecutionError(f"pass {setup.name!r}: the device lacks the Vulkan 1.2 feature shaderOutputLayer "
                                 "(gl_Layer from the vertex shader), which shadow_map needs")
        self.scene = setup.scene
        access = setup.access("shadow_maps")
        layers = access["subresource"]["layers"]
        self.layers = range(layers[0], layers[1]) if setup.layers > 1 else range(0, 1)
        self.count = min(len(self.layers), self.scene.shadow_lights)
        bias = (float(setup.param("shadow.bias_constant", SHADOW_BIAS[0])),
                float(setup.param("shadow.bias_slope", SHADOW_BIAS[1])))
        self.pipeline = setup.graphics_pipeline(
            "scene/shadow_map.vert", None, [self.scene.set_layout], vertex_input=self.scene.position_input,
            push_constant_bytes=16, cull="NONE", depth_test=True, depth_write=True,
            depth_compare="GREATER_OR_EQUAL", depth_bias=bias,
            defines={"SHADOW_LAYERED": 1} if len(self.layers) > 1 else None)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set)])
        for k in range(self.count):
            # light k's matrix, framebuffer layer k (the attachment view starts at the access's first layer)
            rec.push(self.pipeline, pack("4i", k, k, 0, 0))
            self.scene.draw(rec, frame_set, self.setup.param("rgraph.draws"))


@register("light_setup")
class LightSetup(PassImpl):
    """Writes the graph buffer ``lights``: one 64-byte ``Light`` (scene.glsl) per scene light,
    camera-relative, from SceneLights (set 0, binding 3) and the Frame."""

    def __init__(self, setup):
        super().__init__(setup)
        self.scene = setup.scene
        _handle, size = setup.buffer("lights", 0)
        self.count = min(self.scene.lights, size // 64)
        self.sets = setup.descriptors([Binding(0, "storage_buffer", "lights")])
        self.pipeline = setup.compute_pipeline("scene/light_setup.comp", [self.scene.set_layout, self.sets.layout],
                                               push_constant_bytes=16)
        self.push = pack("4i", self.count, 0, 0, 0)
        self.groups = dispatch.groups_2d(self.count, 64)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups, 1)
