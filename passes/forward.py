"""Forward PBR shading: ``forward_pbr`` (the ``forward`` pass of surgery.yaml).

GGX Cook-Torrance (Smith height-correlated visibility, Schlick Fresnel; shaders/forward/brdf.glsl)
for every light of the graph buffer ``lights`` (directional, point and spot with its cone),
PCF shadows on shadow-casting directional lights, split-sum IBL from ``brdf_lut`` and
``env_map`` (passes/ibl.py) and ambient occlusion combine(screen-space ``ao``, the material's
baked AO). Writes ``diffuse`` and ``specular`` (HDR, separate) and ``normal_sss``
(rgb = 0.5 * n + 0.5 of the unit world-space normal, a = the material's sss). Depth is
``depth_read``: GREATER_OR_EQUAL against the prepass (reversed-Z), no depth writes.

Clustered: when the pass reads ``light_grid`` and ``light_indices`` (graphs/surgery_clustered.yaml;
``lights`` then as ``storage_read``, any count) each fragment shades only its froxel's lights
(passes/clustered.py, params ``clusters.*`` and ``lighting.mode``).

Optional reads: without ``ao`` (HBAO culled) the screen-space AO is 1.0, without
``shadow_maps`` (no shadow lights) lights are unshadowed, both by compile-time defines.

Stereo (graph param ``views`` = 2, issue 18): one VK_KHR_multiview render pass draws both eyes
(``multiview``; ``diffuse``, ``specular``, ``normal_sss`` and ``depth`` have a layer per eye);
the shaders take the eye's camera from the scene's Views uniform (``scene_eye(gl_ViewIndex)``:
the view vector, and the froxel depth when clustered) and sample ``ao`` (a 2D-array view, a
layer per eye) at layer ``gl_ViewIndex``. With ``views`` = 1 nothing changes (same defines, same
SPIR-V).

Params: ``forward.ibl_intensity`` (scale of the environment, default 0.5),
``forward.ao_combine`` (0 min (default), 1 max, 2 multiply), ``shadow.pcf_taps`` (PCF taps,
default 16), ``depth_prepass.cull`` (shared with the prepass so both rasterize the same
triangles). NumPy reference of the shading: passes/forward_ref.py.
"""

from __future__ import annotations

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, PassSetup

from .stereo import view_layers

COLOR_OUTPUTS = ("diffuse", "specular", "normal_sss")
LIGHT_BYTES = 64


def light_capacity(light_bytes: int, clustered: bool, max_uniform_range: int) -> int:
    """Lights the shader's ``lights`` array holds: the whole buffer as a storage buffer
    (clustered), else what one uniform-buffer descriptor binds (``maxUniformBufferRange``,
    64 KiB = 1,024 lights on lavapipe and NVIDIA; lights past it are not shaded and
    ``rgraph run`` says so: ``uniform_range_note``)."""
    return (light_bytes if clustered else min(light_bytes, max_uniform_range)) // LIGHT_BYTES


def color_locations(setup: PassSetup, names: tuple[str, ...]) -> dict[str, int]:
    """Fragment output location of each colour attachment (the plan's colour access order)."""
    colors = [a["resource"] for a in setup.plan_pass["accesses"] if a["usage"].startswith("color_attachment")]
    missing = [n for n in names if n not in colors]
    if missing:
        raise ExecutionError(f"pass {setup.name!r}: expected colour attachments {list(names)}, "
                             f"the plan has {colors}")
    if len(colors) != len(names):
        raise ExecutionError(f"pass {setup.name!r}: colour attachments {colors}, expected exactly {list(names)}")
    return {n: colors.index(n) for n in names}


def ao_combine_mode(setup: PassSetup) -> int:
    mode = int(setup.param("forward.ao_combine", 0))
    if mode not in (0, 1, 2):
        raise ExecutionError(f"pass {setup.name!r}: forward.ao_combine must be 0 (min), 1 (max) or 2 (multiply)")
    return mode


@register("forward_pbr")
class ForwardPBR(PassImpl):
    """See the module docstring."""
    param_schema = {
        "forward.ao_combine": Param(int, choices=(0, 1, 2)), "shadow.pcf_taps": Param(int, 1, 64),
        "forward.ibl_intensity": Param(float, 0, 1e3), "depth_prepass.cull": Param(str, choices=("back", "front", "none")),
    }

    clear_values = {"diffuse": (0.0, 0.0, 0.0, 0.0), "specular": (0.0, 0.0, 0.0, 0.0),
                    "normal_sss": (0.5, 0.5, 0.5, 0.0)}
    multiview = True  # views=2: both eyes in one pass (gl_ViewIndex, RGRAPH_VIEWS)

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.scene = scene = setup.scene
        loc = color_locations(setup, COLOR_OUTPUTS)
        _handle, light_bytes = setup.buffer("lights", 0)
        self.has_ao = setup.has("ao")
        stereo = view_layers(setup) > 1
        self.has_shadows = setup.has("shadow_maps") and scene.shadow_lights > 0
        env_mips = int(setup.resource_plan("env_map")["mips"])
        self.clustered = setup.has("light_grid")
        bindings = [Binding(0, "storage_buffer" if self.clustered else "uniform_buffer", "lights"),
                    Binding(1, "sampled", "brdf_lut"), Binding(2, "sampled", "env_map")]
        if self.clustered:
            bindings += [Binding(5, "storage_image", "light_grid", array=True),
                         Binding(6, "storage_buffer", "light_indices")]
        if self.has_ao:
            bindings.append(Binding(3, "sampled", "ao", array=stereo))  # views=2: a layer per eye
        if self.has_shadows:
            bindings.append(Binding(4, "sampled", "shadow_maps", array=True, sampler="nearest"))
        self.sets = setup.descriptors(bindings)
        cull = str(setup.param("depth_prepass.cull", "back")).upper()
        defines = {
            "LOC_DIFFUSE": loc["diffuse"], "LOC_SPECULAR": loc["specular"], "LOC_NORMAL_SSS": loc["normal_sss"],
            "LIGHT_COUNT": max(1, light_capacity(light_bytes, self.clustered, setup.max_uniform_range)),
            "ENV_MIPS": env_mips,
            "HAS_AO": int(self.has_ao), "HAS_SHADOWS": int(self.has_shadows),
            "PCF_TAPS": int(setup.param("shadow.pcf_taps", 16)),
            "IBL_INTENSITY": float(setup.param("forward.ibl_intensity", 0.5)),
            "AO_COMBINE": ao_combine_mode(setup),
        }
        if self.clustered:
            from .clustered import cluster_defines

            defines.update(cluster_defines(setup), CLUSTERED=1)
        self.pipeline = setup.graphics_pipeline(
            "forward/forward.vert", "forward/forward.frag", [scene.set_layout, self.sets.layout], defines=defines,
            vertex_input=scene.vertex_input, cull=cull, front_face="COUNTER_CLOCKWISE", depth_test=True,
            depth_write=False, depth_compare="GREATER_OR_EQUAL")

    def record(self, rec, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.scene.descriptor_set(frame_set), self.sets[frame_set]])
        self.scene.draw(rec, frame_set, self.setup.param("rgraph.draws"))
