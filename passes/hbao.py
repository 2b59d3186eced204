"""HBAO on the async compute queue: reduced-res depth, horizon-based AO, bilateral upsample.

The working resolution is ``hbao.scale`` (default 0.25; ``1 / k`` for an integer ``k``, 1 =
full resolution, where the downsample is a copy and the upsample the identity). The graph
must size ``depth_quarter`` and ``ao_quarter`` with ``{scale: "${params.hbao.scale}"}``;
a size that disagrees with the param is an error at setup.

Three implementations (``impl:`` names), each reading the resources surgery.yaml declares:

- ``hbao_downsample``: ``depth`` (sampled) -> ``depth_quarter`` (storage_write);
- ``hbao``: ``depth_quarter`` (sampled) -> ``ao_quarter`` (storage_write);
- ``hbao_upsample``: ``ao_quarter`` (sampled), ``depth`` (sampled), ``depth_quarter``
  (storage_read) -> ``ao`` (storage_write).

Params: ``hbao.directions``, ``hbao.steps`` (compile-time loop counts), ``hbao.radius``
(world units), ``hbao.angle_bias``, ``hbao.strength``, ``hbao.max_radius_px`` (full-res px),
``hbao.upsample_sharpness``; the camera from ``passes.screenspace_ref.screen_camera``.
What each computes, exactly: ``passes/hbao_ref.py``.

Stereo: with the graph param ``views`` = 2 every image above must have a layer per eye
(``layers: "${params.views}"``); each pass binds them as 2D arrays (``RGRAPH_VIEWS`` in
``shaders/hbao``) and dispatches z = views, invocation z working on layer z alone. Both eyes
use the one projection (``rgraph.scene.instances.eye_view_projs``: the eyes differ by a
translation), so layer k is exactly the views=1 result on layer k.
"""

from __future__ import annotations

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.passkit import Binding, pack

from .hbao_ref import HBAOSettings, quarter_extent
from .screenspace_ref import screen_camera
from .stereo import checked_views, stereo_defines

HBAO_PARAMS = {
    "hbao.directions": Param(int, 1, 64), "hbao.steps": Param(int, 1, 64),
    "hbao.radius": Param(float, 1e-6, 1e6), "hbao.angle_bias": Param(float, 0, 1.5),
    "hbao.strength": Param(float, 0, 100), "hbao.max_radius_px": Param(float, 1, 16384),
    "hbao.upsample_sharpness": Param(float, 0, 1e4), "hbao.scale": Param(float, 1 / 64, 1),
}


def _groups(extent: tuple[int, int]) -> tuple[int, int]:
    return -(-extent[0] // 8), -(-extent[1] // 8)


def _settings(setup) -> HBAOSettings:
    """The pass's settings; checks that the working images have the size ``hbao.scale`` gives."""
    try:
        s = HBAOSettings.from_params(setup.params)
        s.factor  # noqa: B018 - validates hbao.scale
    except ValueError as exc:
        raise ValueError(f"pass {setup.name!r}: {exc}") from None
    full = setup.extent_of("depth") if setup.has("depth") else setup.size
    want = quarter_extent(*full, s.scale)
    for name in ("depth_quarter", "ao_quarter"):
        if setup.has(name) and tuple(setup.extent_of(name)) != want:
            raise ValueError(f"pass {setup.name!r}: {name} is {setup.extent_of(name)} but hbao.scale={s.scale:g} "
                             f"gives {want}; size it {{scale: \"${{params.hbao.scale}}\"}}")
    return s



def _proj(setup) -> bytes:
    cam = screen_camera(setup.plan, setup.params, setup.size)
    return pack("4f", cam.p00, cam.p11, cam.near, 0.0)


@register("hbao_downsample")
class HBAODownsample(PassImpl):
    """Nearest-surface (max reversed-Z) depth of each k x k block (a copy at k = 1)."""
    param_schema = HBAO_PARAMS

    def __init__(self, setup):
        super().__init__(setup)
        self.push = pack("i", _settings(setup).factor)
        views = checked_views(setup, ("depth", "depth_quarter"))
        arr = views > 1
        self.sets = setup.descriptors([Binding(0, "sampled", "depth", sampler="nearest", array=arr),
                                       Binding(1, "storage_image", "depth_quarter", array=arr)])
        self.pipeline = setup.compute_pipeline("hbao/downsample.comp", [self.sets.layout],
                                               push_constant_bytes=len(self.push), defines=stereo_defines(views))
        self.groups = (*_groups(setup.extent_of("depth_quarter")), views)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups)


@register("hbao")
class HBAO(PassImpl):
    """Horizon-based AO at the working resolution."""
    param_schema = HBAO_PARAMS

    def __init__(self, setup):
        super().__init__(setup)
        s = _settings(setup)
        if s.directions < 1 or s.steps < 1:
            raise ValueError(f"pass {setup.name!r}: hbao.directions and hbao.steps must be >= 1")
        views = checked_views(setup, ("depth_quarter", "ao_quarter"))
        arr = views > 1
        self.sets = setup.descriptors([Binding(0, "sampled", "depth_quarter", sampler="nearest", array=arr),
                                       Binding(1, "storage_image", "ao_quarter", array=arr)])
        self.pipeline = setup.compute_pipeline("hbao/hbao.comp", [self.sets.layout], push_constant_bytes=32,
                                               defines={"DIRECTIONS": s.directions, "STEPS": s.steps,
                                                        **stereo_defines(views)})
        self.push = _proj(setup) + pack("4f", s.radius, s.angle_bias, s.strength, s.max_radius_px * s.scale)
        self.groups = (*_groups(setup.extent_of("ao_quarter")), views)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups)


@register("hbao_upsample")
class HBAOUpsample(PassImpl):
    """Depth-aware (joint bilateral) upsample of the working-res AO to full resolution."""
    param_schema = HBAO_PARAMS

    def __init__(self, setup):
        super().__init__(setup)
        s = _settings(setup)
        views = checked_views(setup, ("ao_quarter", "depth", "depth_quarter", "ao"))
        arr = views > 1
        self.sets = setup.descriptors([Binding(0, "sampled", "ao_quarter", sampler="nearest", array=arr),
                                       Binding(1, "sampled", "depth", sampler="nearest", array=arr),
                                       Binding(2, "storage_image", "depth_quarter", array=arr),
                                       Binding(3, "storage_image", "ao", array=arr)])
        self.pipeline = setup.compute_pipeline("hbao/upsample.comp", [self.sets.layout], push_constant_bytes=32,
                                               defines=stereo_defines(views))
        self.push = _proj(setup) + pack("4f", s.upsample_sharpness, 0.0, 0.0, 0.0)
        self.groups = (*_groups(setup.extent_of("ao")), views)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*self.groups)
