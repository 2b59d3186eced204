"""Vulkan synchronization2 vocabulary shared by the mutation tool and the runtime: which
stages can perform an access, and which stages a queue family with given capabilities runs
(the spec's "supported pipeline stages" table). Names as in plans (no prefixes/suffixes)."""

from __future__ import annotations

from collections.abc import Iterable

_SHADER_STAGES = frozenset({
    "VERTEX_SHADER", "TESSELLATION_CONTROL_SHADER", "TESSELLATION_EVALUATION_SHADER", "GEOMETRY_SHADER",
    "TASK_SHADER_EXT", "MESH_SHADER_EXT", "FRAGMENT_SHADER", "COMPUTE_SHADER", "RAY_TRACING_SHADER_KHR",
    "PRE_RASTERIZATION_SHADERS",
})
_TRANSFER_STAGES = frozenset({"COPY", "BLIT", "RESOLVE", "CLEAR", "ALL_TRANSFER", "TRANSFER"})
# access -> stages able to perform it (ALL_COMMANDS supports every access)
ACCESS_STAGES: dict[str, frozenset[str]] = {
    "INDIRECT_COMMAND_READ": frozenset({"DRAW_INDIRECT", "ACCELERATION_STRUCTURE_BUILD_KHR"}),
    "INDEX_READ": frozenset({"INDEX_INPUT", "VERTEX_INPUT"}),
    "VERTEX_ATTRIBUTE_READ": frozenset({"VERTEX_ATTRIBUTE_INPUT", "VERTEX_INPUT"}),
    "UNIFORM_READ": _SHADER_STAGES,
    "SHADER_READ": _SHADER_STAGES | {"ACCELERATION_STRUCTURE_BUILD_KHR"},
    "SHADER_WRITE": _SHADER_STAGES,
    "SHADER_SAMPLED_READ": _SHADER_STAGES,
    "SHADER_STORAGE_READ": _SHADER_STAGES,
    "SHADER_STORAGE_WRITE": _SHADER_STAGES,
    "INPUT_ATTACHMENT_READ": frozenset({"FRAGMENT_SHADER"}),
    "COLOR_ATTACHMENT_READ": frozenset({"COLOR_ATTACHMENT_OUTPUT"}),
    "COLOR_ATTACHMENT_WRITE": frozenset({"COLOR_ATTACHMENT_OUTPUT"}),
    "DEPTH_STENCIL_ATTACHMENT_READ": frozenset({"EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"}),
    "DEPTH_STENCIL_ATTACHMENT_WRITE": frozenset({"EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"}),
    "TRANSFER_READ": _TRANSFER_STAGES | {"ACCELERATION_STRUCTURE_BUILD_KHR"},
    "TRANSFER_WRITE": _TRANSFER_STAGES | {"ACCELERATION_STRUCTURE_BUILD_KHR"},
    "HOST_READ": frozenset({"HOST"}),
    "HOST_WRITE": frozenset({"HOST"}),
    "ACCELERATION_STRUCTURE_READ_KHR": _SHADER_STAGES | {"ACCELERATION_STRUCTURE_BUILD_KHR"},
    "ACCELERATION_STRUCTURE_WRITE_KHR": frozenset({"ACCELERATION_STRUCTURE_BUILD_KHR"}),
}


UNIVERSAL_STAGES = frozenset({"TOP_OF_PIPE", "BOTTOM_OF_PIPE", "ALL_COMMANDS", "HOST", "NONE"})
GRAPHICS_STAGES = frozenset({
    "DRAW_INDIRECT", "VERTEX_INPUT", "INDEX_INPUT", "VERTEX_ATTRIBUTE_INPUT", "VERTEX_SHADER",
    "TESSELLATION_CONTROL_SHADER", "TESSELLATION_EVALUATION_SHADER", "GEOMETRY_SHADER", "TASK_SHADER_EXT",
    "MESH_SHADER_EXT", "PRE_RASTERIZATION_SHADERS", "EARLY_FRAGMENT_TESTS", "FRAGMENT_SHADER",
    "LATE_FRAGMENT_TESTS", "COLOR_ATTACHMENT_OUTPUT", "ALL_GRAPHICS", "FRAGMENT_SHADING_RATE_ATTACHMENT_KHR",
    "TRANSFORM_FEEDBACK_EXT", "CONDITIONAL_RENDERING_EXT",
})
COMPUTE_STAGES = frozenset({
    "DRAW_INDIRECT", "COMPUTE_SHADER", "ACCELERATION_STRUCTURE_BUILD_KHR", "ACCELERATION_STRUCTURE_COPY_KHR",
    "RAY_TRACING_SHADER_KHR", "CONDITIONAL_RENDERING_EXT",
})
CAPABILITIES = frozenset({"graphics", "compute", "transfer"})


def queue_supports(stage: str, capabilities: frozenset[str]) -> bool:
    """Whether a queue family with ``capabilities`` (graphics/compute/transfer) runs ``stage``;
    stages this table does not know are assumed supported."""
    if stage in UNIVERSAL_STAGES or stage in _TRANSFER_STAGES:
        return bool(capabilities)  # graphics and compute families support transfer too
    known = stage in GRAPHICS_STAGES or stage in COMPUTE_STAGES
    return (not known or ("graphics" in capabilities and stage in GRAPHICS_STAGES)
            or ("compute" in capabilities and stage in COMPUTE_STAGES))


def fit_to_queue(stages: Iterable[str], access: Iterable[str],
                 capabilities: frozenset[str]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """One side of a barrier, keeping only the stages the queue runs and the accesses those
    stages perform. A plan barrier's src scope may name another queue's stages (the reads
    before an ownership transfer); a barrier cannot wait for another queue's work anyway
    (the semaphore orders it), and the spec forbids unsupported stages in the mask."""
    kept = tuple(s for s in stages if queue_supports(s, capabilities))
    able = set(supported_accesses(access, kept)) if kept else set()
    kept_access = tuple(a for a in access if a in able)
    return kept, kept_access


def supported_accesses(accesses: Iterable[str], stages: Iterable[str]) -> list[str]:
    """The accesses among ``accesses`` that some stage of ``stages`` can perform."""
    stages = set(stages)
    if "ALL_COMMANDS" in stages:
        return sorted(accesses)
    out = []
    for a in accesses:
        able = ACCESS_STAGES.get(a)
        if a.startswith("MEMORY_") or able is None or able & stages:
            out.append(a)
    return sorted(out)
