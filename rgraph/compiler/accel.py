"""Acceleration structures in the compiler: what each ``kind: accel`` resource holds, its size
from the device's build-size query (or a captured profile), and its build scratch.

An accel resource is one buffer: a bottom-level structure (BLAS) per mesh at 256-byte aligned
offsets, then the top-level structure (TLAS) over the instances. Its geometry is the scene's
meshes, or the probe's known test geometry (``PROBE_BLAS``) when a build pass has no ``impl``,
when the resource says ``geometry: probe`` or when there is no scene. Each build pass also
writes a transient scratch buffer ``NAME.scratch`` (usage ``accel_scratch``), so its memory is
placed, aliased and synchronized like any other transient. A persistent accel is built once
at load; when the scene has deformable meshes its build passes refit it every frame
(``accel_build`` then also reads it).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Protocol

from rgraph.errors import RGraphError
from rgraph.memory_requirements import align_up
from rgraph.spec.specialize import AccessSpec, PassSpec, ResourceSpec, Spec

AS_OFFSET_ALIGNMENT = 256  # VkAccelerationStructureCreateInfoKHR::offset must be a multiple of 256
SCRATCH_SUFFIX = ".scratch"
#: The probe's test geometry: one BLAS (a quad of 2 triangles over 4 vertices), two instances.
PROBE_BLAS = ((2, 3),)  # (triangles, max vertex index)
PROBE_INSTANCES = 2


class AccelSizeProvider(Protocol):
    def accel_sizes(self, level: str, count: int, max_vertex: int, update: bool) -> tuple[int, int, int]: ...

    def accel_scratch_alignment(self) -> int: ...


@dataclass(frozen=True)
class AccelLayout:
    """Where each structure of an accel lives and what building it needs."""

    geometry: str  # "scene" | "probe"
    blas: tuple[tuple[int, int, int, int], ...]  # (triangles, max_vertex, bytes, offset)
    instances: int
    tlas_bytes: int
    tlas_offset: int
    bytes: int  # the whole accel buffer's size
    scratch_bytes: int  # 0: no per-frame build (persistent, no refit)
    update: bool  # persistent + deformable meshes: refitted each frame
    scratch_alignment: int

    def as_plan(self) -> dict:
        return {
            "geometry": self.geometry,
            "blas": [{"triangles": t, "max_vertex": m, "bytes": b, "offset": o} for t, m, b, o in self.blas],
            "tlas": {"instances": self.instances, "bytes": self.tlas_bytes, "offset": self.tlas_offset},
            "scratch_bytes": self.scratch_bytes,
            "scratch_alignment": self.scratch_alignment,
            "refit": self.update,
        }


def refits(res: ResourceSpec, features: dict[str, int]) -> bool:
    return res.lifetime == "persistent" and bool(features.get("deformable_meshes"))


@lru_cache(maxsize=16)
def scene_geometry(scene_path: str) -> tuple[tuple[tuple[int, int], ...], int]:
    """((triangles, max vertex) per mesh, instance count) of a scene file."""
    from rgraph.scene.build import load_scene_data

    data = load_scene_data(scene_path)
    blas = tuple((m.data.triangle_count, max(m.data.vertex_count - 1, 0)) for m in data.meshes)
    return blas, sum(m.instances for m in data.meshes)


def layout_of(res: ResourceSpec, geometry: str, blas_counts, instances: int, update: bool,
              provider: AccelSizeProvider) -> AccelLayout:
    """Sizes from the provider; BLAS scratch regions side by side (one build call), the TLAS
    build reusing the scratch from offset 0 after them."""
    scratch_align = provider.accel_scratch_alignment()
    offset, blas, blas_scratch = 0, [], 0
    for triangles, max_vertex in blas_counts:
        size, build, upd = provider.accel_sizes("bottom", triangles, max_vertex, update)
        blas.append((triangles, max_vertex, size, offset))
        offset = align_up(offset + size, AS_OFFSET_ALIGNMENT)
        blas_scratch += align_up(max(build, upd if update else 0), scratch_align)
    tlas_size, tlas_build, tlas_upd = provider.accel_sizes("top", instances, 0, update)
    # + one alignment: the runtime rounds the scratch buffer's address up to it
    scratch = max(blas_scratch, align_up(max(tlas_build, tlas_upd if update else 0), scratch_align)) + scratch_align
    per_frame = res.lifetime != "persistent" or update
    return AccelLayout(geometry, tuple(blas), instances, tlas_size, offset, offset + tlas_size,
                       scratch if per_frame else 0, update, scratch_align)


def _geometry(res: ResourceSpec, spec: Spec, passes: list[PassSpec]) -> tuple[str, tuple, int]:
    builders = [p for p in passes if any(a.resource == res.name and a.usage == "accel_build" for a in p.accesses)]
    if res.geometry == "probe" or spec.scene_source is None or any(p.impl is None for p in builders):
        return "probe", PROBE_BLAS, PROBE_INSTANCES
    blas, instances = scene_geometry(spec.scene_source)
    if not blas:
        raise RGraphError.at(res.loc, f"accel '{res.name}': the scene has no meshes to build it from")
    return "scene", blas, instances


def used_accels(spec: Spec, passes: list[PassSpec]) -> list[ResourceSpec]:
    """The accels that ``passes`` (the kept ones) touch, by name."""
    used = {a.resource for p in passes for a in p.accesses}
    return [r for n, r in sorted(spec.resources.items()) if r.kind == "accel" and n in used]


def check_geometry(spec: Spec, passes: list[PassSpec]) -> None:
    """What ``rgraph validate`` can tell without a device: every used accel has geometry to be
    built from (the errors of sizing that are not the device's)."""
    for res in used_accels(spec, passes):
        _geometry(res, spec, passes)


def size_culled_accels(spec: Spec, kept: list[PassSpec], culled: list[PassSpec], provider) -> None:
    """Size (in place) each accel that only culled passes touch, so that the plan's ``culled``
    entries report the memory its culling saved (the structure's bytes; its build scratch, a
    transient that would alias, is not counted). Best effort: an accel that cannot be sized
    (no geometry, no provider sizes) keeps its placeholder size, since nothing builds it."""
    if not hasattr(provider, "accel_sizes"):
        return
    kept_names = {r.name for r in used_accels(spec, kept)}
    for res in used_accels(spec, culled):
        if res.name in kept_names or res.accel is not None:
            continue
        try:
            geometry, counts, instances = _geometry(res, spec, culled)
            layout = layout_of(res, geometry, counts, instances, refits(res, spec.features), provider)
        except RGraphError:
            continue
        spec.resources[res.name] = replace(res, bytes=layout.bytes, accel=layout)


def size_accels(spec: Spec, passes: list[PassSpec], provider) -> list[PassSpec]:
    """Size every used accel of ``spec`` (in place) and add its scratch buffer; returns
    ``passes`` with each build pass also writing its accel's scratch, and refits reading."""
    accels = used_accels(spec, passes)
    if not accels:
        return passes
    if not hasattr(provider, "accel_sizes"):
        raise RGraphError.in_file("<device>", "the memory-requirements provider has no acceleration-structure sizes")
    scratch_of: dict[str, str] = {}
    for res in accels:
        geometry, counts, instances = _geometry(res, spec, passes)
        update = refits(res, spec.features)
        try:
            layout = layout_of(res, geometry, counts, instances, update, provider)
        except RGraphError as err:
            raise RGraphError.at(res.loc, f"accel '{res.name}': {err.first.message}") from None
        spec.resources[res.name] = replace(res, bytes=layout.bytes, accel=layout)
        if layout.scratch_bytes:
            name = res.name + SCRATCH_SUFFIX
            if name in spec.resources and spec.resources[name].scratch_of != res.name:
                raise RGraphError.at(spec.resources[name].loc, f"resource name '{name}' is reserved for the build "
                                     f"scratch of accel '{res.name}'")
            spec.resources[name] = ResourceSpec(name, "buffer", "transient", bytes=layout.scratch_bytes, loc=res.loc,
                                                scratch_of=res.name)
            scratch_of[res.name] = name
    out = []
    for p in passes:
        extra, accesses = [], []
        for a in p.accesses:
            res = spec.resources[a.resource]
            if a.usage == "accel_build" and res.accel is not None:
                a = replace(a, refit=res.accel.update)
                if a.resource in scratch_of:
                    extra.append(AccessSpec(scratch_of[a.resource], "accel_scratch", True, None, None, None, False,
                                            a.loc))
            accesses.append(a)
        out.append(replace(p, accesses=tuple(accesses) + tuple(extra)) if extra or accesses != list(p.accesses)
                   else p)
    return out
