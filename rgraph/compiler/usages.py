"""The one table: usage (+ pass kind, explicit stages, format) -> sync2 stages, access, layout.

Everything about synchronization derives from :func:`sync_of`. Names are sync2 names
without prefixes and ``_BIT`` (FORMAT.md section 3).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

# Shader stages of a pass kind, used by sampled/storage/uniform/accel_read usages.
KIND_SHADER_STAGES: dict[str, tuple[str, ...]] = {
    "raster": ("FRAGMENT_SHADER",),
    "compute": ("COMPUTE_SHADER",),
    "raytrace": ("RAY_TRACING_SHADER_KHR",),
    "transfer": ("ALL_TRANSFER",),
}
UNIFORM_RASTER_STAGES = ("FRAGMENT_SHADER", "VERTEX_SHADER")

EXPLICIT_STAGE_NAMES: dict[str, str] = {
    "vertex": "VERTEX_SHADER",
    "tessellation_control": "TESSELLATION_CONTROL_SHADER",
    "tessellation_evaluation": "TESSELLATION_EVALUATION_SHADER",
    "geometry": "GEOMETRY_SHADER",
    "fragment": "FRAGMENT_SHADER",
    "compute": "COMPUTE_SHADER",
    "task": "TASK_SHADER_EXT",
    "mesh": "MESH_SHADER_EXT",
    "raygen": "RAY_TRACING_SHADER_KHR",
    "miss": "RAY_TRACING_SHADER_KHR",
    "closest_hit": "RAY_TRACING_SHADER_KHR",
    "any_hit": "RAY_TRACING_SHADER_KHR",
    "intersection": "RAY_TRACING_SHADER_KHR",
    "callable": "RAY_TRACING_SHADER_KHR",
}

FRAGMENT_TESTS = ("EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS")

# usage -> (fixed stages or None for "shader stages of the pass", access, image layout)
_TABLE: dict[str, tuple[tuple[str, ...] | None, tuple[str, ...], str | None]] = {
    "color_attachment": (("COLOR_ATTACHMENT_OUTPUT",), ("COLOR_ATTACHMENT_WRITE",), "COLOR_ATTACHMENT_OPTIMAL"),
    "color_attachment_blend": (
        ("COLOR_ATTACHMENT_OUTPUT",),
        ("COLOR_ATTACHMENT_READ", "COLOR_ATTACHMENT_WRITE"),
        "COLOR_ATTACHMENT_OPTIMAL",
    ),
    "depth_attachment": (
        FRAGMENT_TESTS,
        ("DEPTH_STENCIL_ATTACHMENT_READ", "DEPTH_STENCIL_ATTACHMENT_WRITE"),
        "DEPTH_ATTACHMENT_OPTIMAL",
    ),
    "depth_read": (FRAGMENT_TESTS, ("DEPTH_STENCIL_ATTACHMENT_READ",), "DEPTH_READ_ONLY_OPTIMAL"),
    "sampled": (None, ("SHADER_SAMPLED_READ",), "SHADER_READ_ONLY_OPTIMAL"),
    "storage_read": (None, ("SHADER_STORAGE_READ",), "GENERAL"),
    "storage_write": (None, ("SHADER_STORAGE_WRITE",), "GENERAL"),
    "storage_rw": (None, ("SHADER_STORAGE_READ", "SHADER_STORAGE_WRITE"), "GENERAL"),
    "uniform": (None, ("UNIFORM_READ",), None),
    "vertex": (("VERTEX_ATTRIBUTE_INPUT",), ("VERTEX_ATTRIBUTE_READ",), None),
    "index": (("INDEX_INPUT",), ("INDEX_READ",), None),
    "indirect": (("DRAW_INDIRECT",), ("INDIRECT_COMMAND_READ",), None),
    # the stage copies run in; the runtime widens it to ALL_TRANSFER for validation layer
    # 1.3.239 (rgraph/vk/lower/workarounds/transfer_stages.py), the plan keeps the true one
    "transfer_src": (("COPY",), ("TRANSFER_READ",), "TRANSFER_SRC_OPTIMAL"),
    "transfer_dst": (("COPY",), ("TRANSFER_WRITE",), "TRANSFER_DST_OPTIMAL"),
    # a build writes the structure (a refit also reads it: ``refit=True``)
    "accel_build": (("ACCELERATION_STRUCTURE_BUILD_KHR",), ("ACCELERATION_STRUCTURE_WRITE_KHR",), None),
    "accel_read": (None, ("ACCELERATION_STRUCTURE_READ_KHR",), None),
    # the build's scratch buffer (added by the compiler to each build pass, never in a graph file)
    "accel_scratch": (
        ("ACCELERATION_STRUCTURE_BUILD_KHR",),
        ("ACCELERATION_STRUCTURE_READ_KHR", "ACCELERATION_STRUCTURE_WRITE_KHR"),
        None,
    ),
}

WRITE_ACCESS = frozenset(
    {
        "COLOR_ATTACHMENT_WRITE",
        "DEPTH_STENCIL_ATTACHMENT_WRITE",
        "SHADER_STORAGE_WRITE",
        "TRANSFER_WRITE",
        "ACCELERATION_STRUCTURE_WRITE_KHR",
    }
)


@dataclass(frozen=True)
class Sync:
    stages: frozenset[str]
    access: frozenset[str]
    layout: str | None

    @cached_property
    def writes(self) -> frozenset[str]:
        return self.access & WRITE_ACCESS

    @cached_property
    def write_scope(self) -> tuple[frozenset[str], frozenset[str]]:
        """(stages, write access): what a later access waits for after this one writes."""
        return self.stages, self.writes


@lru_cache(maxsize=4096)
def sync_of(
    usage: str,
    pass_kind: str,
    *,
    explicit_stages: tuple[str, ...] | None = None,
    is_image: bool = True,
    depth_format: bool = False,
    stencil_format: bool = False,
    refit: bool = False,
) -> Sync:
    """Stages, access and layout of one usage in a pass of ``pass_kind``."""
    stages, access, layout = _TABLE[usage]
    if refit and usage == "accel_build":
        access = (*access, "ACCELERATION_STRUCTURE_READ_KHR")
    if stages is None:
        if explicit_stages:
            stages = tuple(EXPLICIT_STAGE_NAMES[s] for s in explicit_stages)
        elif usage == "uniform" and pass_kind == "raster":
            stages = UNIFORM_RASTER_STAGES
        else:
            stages = KIND_SHADER_STAGES[pass_kind]
    if not is_image:
        layout = None
    elif depth_format and layout in ("SHADER_READ_ONLY_OPTIMAL", "DEPTH_READ_ONLY_OPTIMAL"):
        # depth read + sampled share one read-only layout: no transition between them
        layout = "DEPTH_STENCIL_READ_ONLY_OPTIMAL" if stencil_format else "DEPTH_READ_ONLY_OPTIMAL"
    elif stencil_format and layout == "DEPTH_ATTACHMENT_OPTIMAL":
        layout = "DEPTH_STENCIL_ATTACHMENT_OPTIMAL"
    return Sync(frozenset(stages), frozenset(access), layout)


def merge(a: Sync, b: Sync) -> Sync:
    """Two usages of one subresource in one pass (same layout, checked at validation)."""
    assert a.layout == b.layout, (a, b)
    return Sync(a.stages | b.stages, a.access | b.access, a.layout)
