"""Separable screen-space subsurface scattering: ``sss_blur`` (raster, full-screen triangle).

One implementation for both passes of surgery.yaml:

- ``sss_blur_h``: reads ``diffuse``, ``depth``, ``normal_sss`` (sampled), writes ``sss_tmp``;
- ``sss_blur_v``: reads ``sss_tmp``, ``depth``, ``normal_sss`` (sampled), writes ``diffuse``.

The direction is the pass param ``sss.direction`` (``h`` or ``v``) when given, else it
follows from the resources (reading ``sss_tmp`` means vertical). ``sss.kernel``:
``separable`` (default) or ``2d``: the non-separable 2D convolution of the same profile
(the reference of ``rgraph sweep``), done whole by the ``h`` pass while the ``v`` pass
copies ``sss_tmp`` to ``diffuse``, so graph and synchronization stay identical. Params:
``sss.samples`` (11, 17 or 25; 2D: the grid's samples per axis), ``sss.width`` (world units of the kernel's [-3, 3] at SSS strength 1),
``sss.follow_depth`` (world depth difference that fully rejects a tap). The SSS strength is
``normal_sss.a``; the camera projection comes from ``passes.screenspace_ref.screen_camera``.
What it computes, exactly: ``passes/sss_ref.py``.

Stereo (graph param ``views`` = 2, issue 18): every image has a layer per eye. A full-screen
pass, so not VK_KHR_multiview (lavapipe crashes executing a multiview render pass with colour
attachments only; passes/tonemap.py): one layered framebuffer, one full-screen instance per
layer (``FULLSCREEN_LAYERS``, ``gl_Layer``), the inputs bound as 2D-array views and read at the
fragment's layer. Both eyes share the projection, so the kernel is the same. With ``views`` = 1
nothing changes.
"""

from __future__ import annotations

import numpy as np

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.passkit import Binding

from .screenspace_ref import screen_camera
from .sss_ref import SSSSettings, kernel, kernel_2d
from .stereo import view_layers


def direction_of(setup) -> str:
    """``h`` or ``v``: the ``sss.direction`` param, else from which colour resource is read."""
    given = setup.params.get("sss.direction")
    if given is not None:
        if str(given) not in ("h", "v"):
            raise ValueError(f"pass {setup.name!r}: sss.direction must be 'h' or 'v', not {given!r}")
        return str(given)
    return "v" if setup.has("sss_tmp") and setup.access("sss_tmp")["usage"] == "sampled" else "h"


@register("sss_blur")
class SSSBlur(PassImpl):
    """One direction of the separable SSS blur (or, with ``sss.kernel=2d``, the whole 2D blur
    in the ``h`` pass and a copy in the ``v`` pass), written to the pass's colour attachment."""
    param_schema = {
        "sss.samples": Param(int, choices=(11, 17, 25)), "sss.kernel": Param(str, choices=("separable", "2d")),
        "sss.width": Param(float, 0, 1e3), "sss.follow_depth": Param(float, 0, 1e3),
        "sss.direction": Param(str, choices=("h", "v")),
    }

    def __init__(self, setup):
        super().__init__(setup)
        try:
            s = SSSSettings.from_params(setup.params)
        except ValueError as exc:
            raise ValueError(f"pass {setup.name!r}: {exc}") from None
        self.direction = direction_of(setup)
        source = "sss_tmp" if self.direction == "v" else "diffuse"
        target = next(a["resource"] for a in setup.plan_pass["accesses"] if a["usage"].startswith("color_attachment"))
        width, height = setup.extent_of(target)
        cam = screen_camera(setup.plan, setup.params, setup.size)
        scale_x, scale_y = abs(cam.p00) * width / 2.0 / 3.0, abs(cam.p11) * height / 2.0 / 3.0
        defines = {"SAMPLES": s.samples, "HORIZONTAL": int(self.direction == "h")}
        if s.kernel == "2d":
            taps2d = kernel_2d(s.samples, s.strength, s.falloff)
            interleaved = np.zeros((len(taps2d), 2, 4), np.float32)
            interleaved[:, 0, :3], interleaved[:, 1, :2] = taps2d[:, :3], taps2d[:, 3:5]
            params = np.array([s.width, s.follow_depth, scale_x, cam.near, scale_y, 0, 0, 0], np.float32)
            data = np.concatenate([interleaved.reshape(-1), params]).tobytes()
            defines.update({"KERNEL_2D": 1, "TAPS": len(taps2d), "COPY": int(self.direction == "v")})
        else:
            taps = kernel(s.samples, s.strength, s.falloff).astype(np.float32)
            params = np.array([s.width, s.follow_depth, scale_x if self.direction == "h" else scale_y, cam.near],
                              np.float32)
            data = np.concatenate([taps.reshape(-1), params]).tobytes()
        self.uniform = setup.host_buffer(len(data))
        self.uniform.write(data)
        self.layers = view_layers(setup)
        stereo = self.layers > 1
        if stereo:
            defines["FULLSCREEN_LAYERS"] = self.layers
        self.sets = setup.descriptors([
            Binding(0, "sampled", source, sampler="linear", array=stereo),
            Binding(1, "sampled", "depth", sampler="nearest", array=stereo),
            Binding(2, "sampled", "normal_sss", sampler="nearest", array=stereo),
            Binding(3, "uniform_buffer", buffers=((self.uniform.handle, len(data)),))])
        self.pipeline = setup.graphics_pipeline(
            "lib/fullscreen.vert", "sss/blur.frag", [self.sets.layout], defines=defines)

    def record(self, rec, frame_set):
        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.draw(3, self.layers)
