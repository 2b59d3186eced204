"""Synchronization2 vocabulary as bit tables: stages, accesses, layouts.

This is the checker's own copy, independent of the barrier generator. Names are the
Vulkan sync2 names without ``VK_PIPELINE_STAGE_2_`` / ``VK_ACCESS_2_`` /
``VK_IMAGE_LAYOUT_`` prefixes and ``_BIT`` suffixes. Meta names (``ALL_COMMANDS``,
``SHADER_READ``, ...) expand to the concrete bits they stand for.
"""

from __future__ import annotations

from collections.abc import Iterable

# --- pipeline stages ---------------------------------------------------------------

CONCRETE_STAGES: tuple[str, ...] = (
    "DRAW_INDIRECT",
    "INDEX_INPUT",
    "VERTEX_ATTRIBUTE_INPUT",
    "VERTEX_SHADER",
    "TESSELLATION_CONTROL_SHADER",
    "TESSELLATION_EVALUATION_SHADER",
    "GEOMETRY_SHADER",
    "TASK_SHADER_EXT",
    "MESH_SHADER_EXT",
    "FRAGMENT_SHADER",
    "EARLY_FRAGMENT_TESTS",
    "LATE_FRAGMENT_TESTS",
    "COLOR_ATTACHMENT_OUTPUT",
    "COMPUTE_SHADER",
    "COPY",
    "BLIT",
    "RESOLVE",
    "CLEAR",
    "HOST",
    "ACCELERATION_STRUCTURE_BUILD_KHR",
    "ACCELERATION_STRUCTURE_COPY_KHR",
    "RAY_TRACING_SHADER_KHR",
    "CONDITIONAL_RENDERING_EXT",
    "TRANSFORM_FEEDBACK_EXT",
    "FRAGMENT_SHADING_RATE_ATTACHMENT_KHR",
    "FRAGMENT_DENSITY_PROCESS_EXT",
    "COMMAND_PREPROCESS_EXT",
    "VIDEO_DECODE_KHR",
    "VIDEO_ENCODE_KHR",
    "MICROMAP_BUILD_EXT",
    "OPTICAL_FLOW_NV",
    "SUBPASS_SHADER_HUAWEI",
    "INVOCATION_MASK_HUAWEI",
    "CLUSTER_CULLING_SHADER_HUAWEI",
)
STAGE_BIT: dict[str, int] = {name: 1 << i for i, name in enumerate(CONCRETE_STAGES)}
ALL_STAGES = (1 << len(CONCRETE_STAGES)) - 1


def _stages(*names: str) -> int:
    mask = 0
    for name in names:
        mask |= STAGE_BIT[name]
    return mask


VERTEX_INPUT = _stages("INDEX_INPUT", "VERTEX_ATTRIBUTE_INPUT")
PRE_RASTERIZATION = _stages(
    "VERTEX_SHADER", "TESSELLATION_CONTROL_SHADER", "TESSELLATION_EVALUATION_SHADER",
    "GEOMETRY_SHADER", "TASK_SHADER_EXT", "MESH_SHADER_EXT",
)
ALL_TRANSFER = _stages("COPY", "BLIT", "RESOLVE", "CLEAR", "ACCELERATION_STRUCTURE_COPY_KHR")
ALL_GRAPHICS = (
    _stages(
        "DRAW_INDIRECT", "FRAGMENT_SHADER", "EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS",
        "COLOR_ATTACHMENT_OUTPUT", "CONDITIONAL_RENDERING_EXT", "TRANSFORM_FEEDBACK_EXT",
        "FRAGMENT_SHADING_RATE_ATTACHMENT_KHR", "FRAGMENT_DENSITY_PROCESS_EXT",
        "SUBPASS_SHADER_HUAWEI", "INVOCATION_MASK_HUAWEI", "CLUSTER_CULLING_SHADER_HUAWEI",
    )
    | VERTEX_INPUT
    | PRE_RASTERIZATION
)

# Meta stages and aliases. TOP_OF_PIPE / BOTTOM_OF_PIPE depend on the scope they are in.
STAGE_META: dict[str, int] = {
    "NONE": 0,
    "ALL_COMMANDS": ALL_STAGES,
    "ALL_GRAPHICS": ALL_GRAPHICS,
    "ALL_TRANSFER": ALL_TRANSFER,
    "TRANSFER": ALL_TRANSFER,
    "PRE_RASTERIZATION_SHADERS": PRE_RASTERIZATION,
    "VERTEX_INPUT": VERTEX_INPUT,
    "TASK_SHADER_NV": STAGE_BIT["TASK_SHADER_EXT"],
    "MESH_SHADER_NV": STAGE_BIT["MESH_SHADER_EXT"],
    "RAY_TRACING_SHADER_NV": STAGE_BIT["RAY_TRACING_SHADER_KHR"],
    "ACCELERATION_STRUCTURE_BUILD_NV": STAGE_BIT["ACCELERATION_STRUCTURE_BUILD_KHR"],
    "SHADING_RATE_IMAGE_NV": STAGE_BIT["FRAGMENT_SHADING_RATE_ATTACHMENT_KHR"],
    "COMMAND_PREPROCESS_NV": STAGE_BIT["COMMAND_PREPROCESS_EXT"],
}
FIRST_SCOPE_ONLY = {"TOP_OF_PIPE": 0, "BOTTOM_OF_PIPE": ALL_STAGES}
SECOND_SCOPE_ONLY = {"TOP_OF_PIPE": ALL_STAGES, "BOTTOM_OF_PIPE": 0}
KNOWN_STAGE_NAMES = frozenset(STAGE_BIT) | frozenset(STAGE_META) | frozenset(FIRST_SCOPE_ONLY)

# --- accesses ----------------------------------------------------------------------

READ_ACCESSES: tuple[str, ...] = (
    "INDIRECT_COMMAND_READ",
    "INDEX_READ",
    "VERTEX_ATTRIBUTE_READ",
    "UNIFORM_READ",
    "INPUT_ATTACHMENT_READ",
    "SHADER_SAMPLED_READ",
    "SHADER_STORAGE_READ",
    "SHADER_BINDING_TABLE_READ_KHR",
    "COLOR_ATTACHMENT_READ",
    "COLOR_ATTACHMENT_READ_NONCOHERENT_EXT",
    "DEPTH_STENCIL_ATTACHMENT_READ",
    "TRANSFER_READ",
    "HOST_READ",
    "ACCELERATION_STRUCTURE_READ_KHR",
    "CONDITIONAL_RENDERING_READ_EXT",
    "TRANSFORM_FEEDBACK_COUNTER_READ_EXT",
    "FRAGMENT_SHADING_RATE_ATTACHMENT_READ_KHR",
    "FRAGMENT_DENSITY_MAP_READ_EXT",
    "COMMAND_PREPROCESS_READ_EXT",
    "DESCRIPTOR_BUFFER_READ_EXT",
    "INVOCATION_MASK_READ_HUAWEI",
    "MICROMAP_READ_EXT",
    "VIDEO_DECODE_READ_KHR",
    "VIDEO_ENCODE_READ_KHR",
    "OPTICAL_FLOW_READ_NV",
)
WRITE_ACCESSES: tuple[str, ...] = (
    "SHADER_STORAGE_WRITE",
    "COLOR_ATTACHMENT_WRITE",
    "DEPTH_STENCIL_ATTACHMENT_WRITE",
    "TRANSFER_WRITE",
    "HOST_WRITE",
    "ACCELERATION_STRUCTURE_WRITE_KHR",
    "TRANSFORM_FEEDBACK_WRITE_EXT",
    "TRANSFORM_FEEDBACK_COUNTER_WRITE_EXT",
    "COMMAND_PREPROCESS_WRITE_EXT",
    "MICROMAP_WRITE_EXT",
    "VIDEO_DECODE_WRITE_KHR",
    "VIDEO_ENCODE_WRITE_KHR",
    "OPTICAL_FLOW_WRITE_NV",
)
ACCESS_BIT: dict[str, int] = {name: 1 << i for i, name in enumerate(READ_ACCESSES + WRITE_ACCESSES)}
READ_MASK = sum(ACCESS_BIT[n] for n in READ_ACCESSES)
WRITE_MASK = sum(ACCESS_BIT[n] for n in WRITE_ACCESSES)
ACCESS_META: dict[str, int] = {
    "NONE": 0,
    "MEMORY_READ": READ_MASK,
    "MEMORY_WRITE": WRITE_MASK,
    "SHADER_READ": ACCESS_BIT["SHADER_SAMPLED_READ"] | ACCESS_BIT["SHADER_STORAGE_READ"]
    | ACCESS_BIT["SHADER_BINDING_TABLE_READ_KHR"],
    "SHADER_WRITE": ACCESS_BIT["SHADER_STORAGE_WRITE"],
    "ACCELERATION_STRUCTURE_READ_NV": ACCESS_BIT["ACCELERATION_STRUCTURE_READ_KHR"],
    "ACCELERATION_STRUCTURE_WRITE_NV": ACCESS_BIT["ACCELERATION_STRUCTURE_WRITE_KHR"],
    "COMMAND_PREPROCESS_READ_NV": ACCESS_BIT["COMMAND_PREPROCESS_READ_EXT"],
    "COMMAND_PREPROCESS_WRITE_NV": ACCESS_BIT["COMMAND_PREPROCESS_WRITE_EXT"],
    "SHADING_RATE_IMAGE_READ_NV": ACCESS_BIT["FRAGMENT_SHADING_RATE_ATTACHMENT_READ_KHR"],
}
KNOWN_ACCESS_NAMES = frozenset(ACCESS_BIT) | frozenset(ACCESS_META)

# --- image layouts -----------------------------------------------------------------

LAYOUTS = frozenset({
    "UNDEFINED", "GENERAL", "PREINITIALIZED",
    "COLOR_ATTACHMENT_OPTIMAL", "DEPTH_STENCIL_ATTACHMENT_OPTIMAL", "DEPTH_STENCIL_READ_ONLY_OPTIMAL",
    "SHADER_READ_ONLY_OPTIMAL", "TRANSFER_SRC_OPTIMAL", "TRANSFER_DST_OPTIMAL",
    "DEPTH_READ_ONLY_STENCIL_ATTACHMENT_OPTIMAL", "DEPTH_ATTACHMENT_STENCIL_READ_ONLY_OPTIMAL",
    "DEPTH_ATTACHMENT_OPTIMAL", "DEPTH_READ_ONLY_OPTIMAL",
    "STENCIL_ATTACHMENT_OPTIMAL", "STENCIL_READ_ONLY_OPTIMAL",
    "READ_ONLY_OPTIMAL", "ATTACHMENT_OPTIMAL",
    "PRESENT_SRC_KHR", "SHARED_PRESENT_KHR",
    "FRAGMENT_SHADING_RATE_ATTACHMENT_OPTIMAL_KHR", "FRAGMENT_DENSITY_MAP_OPTIMAL_EXT",
    "ATTACHMENT_FEEDBACK_LOOP_OPTIMAL_EXT", "RENDERING_LOCAL_READ_KHR",
    "VIDEO_DECODE_DST_KHR", "VIDEO_DECODE_SRC_KHR", "VIDEO_DECODE_DPB_KHR",
    "VIDEO_ENCODE_DST_KHR", "VIDEO_ENCODE_SRC_KHR", "VIDEO_ENCODE_DPB_KHR",
})
UNDEFINED = "UNDEFINED"

# --- expansion and naming ------------------------------------------------------------

SCOPE_ACCESS = "access"  # an access's own stages: TOP/BOTTOM_OF_PIPE name no real work
SCOPE_FIRST = "first"
SCOPE_SECOND = "second"


def stage_mask(names: Iterable[str], scope: str) -> int:
    """Concrete stage bits for a list of stage names in a given scope position."""
    mask = 0
    for name in names:
        if name in STAGE_BIT:
            mask |= STAGE_BIT[name]
        elif name in STAGE_META:
            mask |= STAGE_META[name]
        elif scope == SCOPE_FIRST:
            mask |= FIRST_SCOPE_ONLY[name]
        elif scope == SCOPE_SECOND:
            mask |= SECOND_SCOPE_ONLY[name]
    return mask


def access_mask(names: Iterable[str]) -> int:
    mask = 0
    for name in names:
        mask |= ACCESS_BIT[name] if name in ACCESS_BIT else ACCESS_META[name]
    return mask


def bits(mask: int) -> Iterable[int]:
    """Each set bit of ``mask`` as its own mask, lowest first."""
    while mask:
        low = mask & -mask
        yield low
        mask ^= low


_STAGE_NAMES = {bit: name for name, bit in STAGE_BIT.items()}
_ACCESS_NAMES = {bit: name for name, bit in ACCESS_BIT.items()}


def stage_names(mask: int) -> str:
    """``A|B`` for a stage mask, folding the meta names a plan would use."""
    if mask == 0:
        return "NONE"
    if mask == ALL_STAGES:
        return "ALL_COMMANDS"
    parts = []
    for meta_name, meta in (("ALL_TRANSFER", ALL_TRANSFER),):
        if mask & meta == meta:
            parts.append(meta_name)
            mask &= ~meta
    parts += [_STAGE_NAMES[b] for b in bits(mask)]
    return "|".join(parts)


def access_names(mask: int) -> str:
    if mask == 0:
        return "NONE"
    if mask == READ_MASK | WRITE_MASK:
        return "MEMORY_READ|MEMORY_WRITE"
    if mask == WRITE_MASK:
        return "MEMORY_WRITE"
    if mask == READ_MASK:
        return "MEMORY_READ"
    return "|".join(_ACCESS_NAMES[b] for b in bits(mask))
