"""Bloom at reduced resolution: ``bloom_bright``, ``bloom_blur`` (h or v), ``bloom_combine``.

Params: ``bloom.threshold`` (1.0), ``bloom.knee`` (0.5, soft-knee width as a fraction of the
threshold), ``bloom.clamp`` (65504, what +Inf and larger values become before the Karis
average), ``bloom.radius`` (16, truncation radius in HDR pixels: round(radius / f) taps each
side at reduction factor f, at most 28), ``bloom.sigma`` (radius/2, HDR pixels),
``bloom.direction`` (``h`` or ``v``; pass-level, required by ``bloom_blur``),
``bloom.intensity`` (0.05). Reference and the non-finite rule: ``bloom_ref``.

Stereo: with the graph param ``views`` = 2 every image these passes touch (``hdr``,
``bloom_a``, ``bloom_b``) must have a layer per eye (``layers: "${params.views}"``). The
compute passes bind them as 2D arrays (``RGRAPH_VIEWS``) and dispatch z = views, one layer
per z; ``bloom_combine`` draws one full-screen instance per layer into the layered ``hdr``
framebuffer (``lib/fullscreen.vert`` ``FULLSCREEN_LAYERS``, as ``tonemap_filmic``; not
VK_KHR_multiview, which lavapipe crashes on with only a colour attachment) and samples the
bloom layer of its own layer. Layer k is exactly the views=1 result on layer k.
"""

from __future__ import annotations

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.errors import ExecutionError
from rgraph.vk.passkit import Binding, pack

from .bloom_ref import MAX_RADIUS, gaussian_weights, working_blur
from .post_common_ref import HALF_MAX
from .stereo import checked_views, stereo_defines


def _one(setup, usage: str) -> str:
    """The single resource this pass accesses with ``usage``."""
    found = [a["resource"] for a in setup.plan_pass["accesses"] if a["usage"] == usage]
    if len(found) != 1:
        raise ExecutionError(f"pass {setup.name!r}: expects exactly one {usage} resource, has {found or 'none'}")
    return found[0]


def _factor(big: tuple[int, int], small: tuple[int, int]) -> tuple[int, int]:
    return max(1, big[0] // small[0]), max(1, big[1] // small[1])


def _groups(extent: tuple[int, int]) -> tuple[int, int]:
    return -(-extent[0] // 8), -(-extent[1] // 8)



@register("bloom_bright")
class BloomBright(PassImpl):
    """Reads its sampled source (``hdr``), writes its storage image (``bloom_a``) at reduced size."""
    param_schema = {
        "bloom.threshold": Param(float, 0, 65504), "bloom.knee": Param(float, 0, 65504),
        "bloom.clamp": Param(float, 0, 65504), "bloom.scale": Param(float, 1 / 64, 1),
    }

    def __init__(self, setup):
        super().__init__(setup)
        src, dst = _one(setup, "sampled"), _one(setup, "storage_write")
        self.extent = setup.extent_of(dst)
        fx, fy = _factor(setup.extent_of(src), self.extent)
        threshold = float(setup.param("bloom.threshold", 1.0))
        knee = float(setup.param("bloom.knee", 0.5))
        clamp = float(setup.param("bloom.clamp", HALF_MAX))
        if threshold < 0 or knee < 0 or not clamp > 0:
            raise ExecutionError(f"pass {setup.name!r}: bloom.threshold and bloom.knee must be >= 0 and "
                                 f"bloom.clamp > 0 (got {threshold}, {knee}, {clamp})")
        self.push = pack("2i3f", fx, fy, threshold, knee, clamp)
        self.views = checked_views(setup, (src, dst))
        arr = self.views > 1
        self.sets = setup.descriptors([Binding(0, "sampled", src, sampler="nearest", array=arr),
                                       Binding(1, "storage_image", dst, array=arr)])
        self.pipeline = setup.compute_pipeline("post/bloom_bright.comp", [self.sets.layout],
                                               push_constant_bytes=len(self.push), defines=stereo_defines(self.views))

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*_groups(self.extent), self.views)


@register("bloom_blur")
class BloomBlur(PassImpl):
    """One separable Gaussian pass from its sampled source to its storage image (same size);
    radius and sigma given in HDR pixels, divided by the reduction factor along its axis."""
    param_schema = {
        "bloom.direction": Param(str, choices=("h", "v")), "bloom.sigma": Param(float, 1e-3, 1024),
        "bloom.radius": Param(float, 0, 1024), "bloom.scale": Param(float, 1 / 64, 1),
    }

    def __init__(self, setup):
        super().__init__(setup)
        src, dst = _one(setup, "sampled"), _one(setup, "storage_write")
        direction = setup.param("bloom.direction")
        if direction not in ("h", "v"):
            raise ExecutionError(f"pass {setup.name!r}: pass-level param bloom.direction must be 'h' or 'v', "
                                 f"got {direction!r}")
        sigma = setup.param("bloom.sigma")
        self.extent = setup.extent_of(dst)
        factor = _factor(setup.size, self.extent)[0 if direction == "h" else 1]
        try:
            radius, sigma_texels = working_blur(float(setup.param("bloom.radius", 16)),
                                                None if sigma is None else float(sigma), factor)
            weights = gaussian_weights(radius, sigma_texels)
        except ValueError as exc:
            raise ExecutionError(f"pass {setup.name!r}: {exc} (at reduction factor {factor})") from None
        padded = list(weights) + [0.0] * (MAX_RADIUS + 1 - len(weights))
        self.push = pack("3i29f", *((1, 0) if direction == "h" else (0, 1)), radius, *padded)
        self.views = checked_views(setup, (src, dst))
        arr = self.views > 1
        self.sets = setup.descriptors([Binding(0, "sampled", src, sampler="nearest", array=arr),
                                       Binding(1, "storage_image", dst, array=arr)])
        self.pipeline = setup.compute_pipeline("post/bloom_blur.comp", [self.sets.layout],
                                               push_constant_bytes=len(self.push), defines=stereo_defines(self.views))

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.dispatch(*_groups(self.extent), self.views)


@register("bloom_combine")
class BloomCombine(PassImpl):
    """Adds ``bloom.intensity`` times its sampled bloom image (bilinear) to its blended attachment."""
    param_schema = {"bloom.intensity": Param(float, 0, 1e3), "bloom.scale": Param(float, 1 / 64, 1)}

    def __init__(self, setup):
        super().__init__(setup)
        src = _one(setup, "sampled")
        dst = _one(setup, "color_attachment_blend")
        bw, bh = setup.extent_of(src)
        fx, fy = _factor(setup.extent, (bw, bh))
        self.push = pack("3f", 1.0 / (fx * bw), 1.0 / (fy * bh), float(setup.param("bloom.intensity", 0.05)))
        self.views = checked_views(setup, (src, dst))
        stereo = self.views > 1
        self.sets = setup.descriptors([Binding(0, "sampled", src, sampler="linear", array=stereo)])
        # views=2: one full-screen instance per layer of the layered hdr framebuffer (gl_Layer)
        defines = {"FULLSCREEN_LAYERS": self.views, **stereo_defines(self.views)} if stereo else None
        self.pipeline = setup.graphics_pipeline("lib/fullscreen.vert", "post/bloom_combine.frag", [self.sets.layout],
                                                push_constant_bytes=len(self.push), blend=["add"], defines=defines)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, self.push)
        rec.draw(3, self.views)
