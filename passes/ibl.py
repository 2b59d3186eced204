"""Image-based lighting inputs, built by compute passes into persistent resources.

- ``ibl_brdf_lut`` writes ``brdf_lut`` (r16g16_sfloat, lut_size^2): the split-sum GGX BRDF
  integral (A, B) over (N.V, roughness), ``ibl.samples`` Hammersley importance samples;
- ``ibl_prefilter`` writes every mip of ``env_map`` (r16g16b16a16_sfloat equirectangular,
  2:1): the procedural operating-room environment (shaders/ibl/environment.glsl) prefiltered
  with GGX for roughness mip / (mips - 1), one storage-image descriptor set per mip.

Both are static: with ``ibl.static`` = 1 (default) they dispatch in the first frame only
(an indirect dispatch whose group counts ``update`` zeroes afterwards: command buffers are
recorded once), so the persistent results are built once per run. ``ibl.static`` = 0
rebuilds every frame (for timing sweeps). References: ``passes/ibl_ref.py``.
"""

from __future__ import annotations

import struct

from rgraph.impl import Param, PassImpl, register
from rgraph.vk.loader import vk
from rgraph.vk.passkit import Binding, PassSetup, pack

GROUP = 8


def _groups(extent: tuple[int, int]) -> tuple[int, int, int]:
    return -(-extent[0] // GROUP), -(-extent[1] // GROUP), 1


class _BuildOnce:
    """Indirect dispatch arguments per frame-in-flight set: real counts in the first frame
    (or every frame when not static), zero groups afterwards."""

    def __init__(self, setup: PassSetup, groups: list[tuple[int, int, int]]) -> None:
        v = vk()
        self.static = bool(int(setup.param("ibl.static", 1)))
        self.groups = groups
        flags = v.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT
        self.buffers = [setup.host_buffer(12 * len(groups), flags) for _ in range(setup.sets)]
        for buf in self.buffers:
            buf.write(self._args(True))
        self._building = [True] * setup.sets  # per set: its buffer holds the real counts

    def _args(self, build: bool) -> bytes:
        return b"".join(struct.pack("<3I", *(g if build else (0, 0, 0))) for g in self.groups)

    def update(self, frame: int, frame_set: int) -> None:
        """Set ``frame_set``'s arguments for ``frame``, written only when they change."""
        build = not self.static or frame == 0
        if build != self._building[frame_set]:
            self.buffers[frame_set].write(self._args(build))
            self._building[frame_set] = build

    def dispatch(self, rec, frame_set: int, index: int) -> None:
        rec.dispatch_indirect(self.buffers[frame_set].handle, 12 * index)


@register("ibl_brdf_lut")
class BrdfLut(PassImpl):
    """Split-sum BRDF LUT (Karis 2013, Smith height-correlated visibility) into ``brdf_lut``."""
    param_schema = {"ibl.static": Param(bool), "ibl.samples": Param(int, 1, 65536)}

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.samples = int(setup.param("ibl.samples", 128))
        self.sets = setup.descriptors([Binding(0, "storage_image", "brdf_lut")])
        self.pipeline = setup.compute_pipeline("ibl/brdf_lut.comp", [self.sets.layout],
                                               defines={"SAMPLES": self.samples})
        self.build = _BuildOnce(setup, [_groups(setup.extent_of("brdf_lut"))])

    def update(self, frame: int, frame_set: int) -> None:
        self.build.update(frame, frame_set)

    def record(self, rec, frame_set: int) -> None:
        rec.bind(self.pipeline, [self.sets[frame_set]])
        self.build.dispatch(rec, frame_set, 0)


@register("ibl_prefilter")
class Prefilter(PassImpl):
    """GGX-prefiltered procedural environment into every mip of ``env_map``."""
    param_schema = {"ibl.static": Param(bool), "ibl.samples": Param(int, 1, 65536)}

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.samples = int(setup.param("ibl.samples", 128))
        self.mips = int(setup.resource_plan("env_map")["mips"])
        self.per_mip = [setup.descriptors([Binding(0, "storage_image", "env_map", mips=(m, m + 1))])
                        for m in range(self.mips)]
        self.pipeline = setup.compute_pipeline("ibl/prefilter.comp", [self.per_mip[0].layout],
                                               defines={"SAMPLES": self.samples}, push_constant_bytes=4)
        self.build = _BuildOnce(setup, [_groups(setup.extent_of("env_map", m)) for m in range(self.mips)])

    def roughness(self, mip: int) -> float:
        return mip / max(self.mips - 1, 1)

    def update(self, frame: int, frame_set: int) -> None:
        self.build.update(frame, frame_set)

    def record(self, rec, frame_set: int) -> None:
        for m, sets in enumerate(self.per_mip):
            rec.bind(self.pipeline, [sets[frame_set]])
            rec.push(self.pipeline, pack("f", self.roughness(m)))
            self.build.dispatch(rec, frame_set, m)
