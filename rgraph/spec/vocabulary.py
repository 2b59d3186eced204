"""The closed vocabularies of the graph file: usages, pass kinds, queues, stages, features."""

from __future__ import annotations

from typing import Literal, get_args

UsageName = Literal[
    "color_attachment",
    "color_attachment_blend",
    "depth_attachment",
    "depth_read",
    "sampled",
    "storage_read",
    "storage_write",
    "storage_rw",
    "uniform",
    "vertex",
    "index",
    "indirect",
    "transfer_src",
    "transfer_dst",
    "accel_build",
    "accel_read",
]
PassKind = Literal["raster", "compute", "raytrace", "transfer"]
QueueName = Literal["graphics", "compute", "transfer"]
Lifetime = Literal["transient", "persistent", "imported", "output"]
ResourceKind = Literal["image", "buffer", "accel"]
ShaderStage = Literal[
    "vertex", "tessellation_control", "tessellation_evaluation", "geometry", "fragment",
    "compute", "task", "mesh", "raygen", "miss", "closest_hit", "any_hit", "intersection", "callable",
]
SceneFeature = Literal[
    "lights", "point_lights", "shadow_lights", "sss_materials", "decals", "reflective_materials",
    "refractive_materials", "transparent_materials", "deformable_meshes", "large_world",
]

USAGES: tuple[str, ...] = get_args(UsageName)
PASS_KINDS: tuple[str, ...] = get_args(PassKind)
QUEUES: tuple[str, ...] = get_args(QueueName)
SCENE_FEATURES: tuple[str, ...] = get_args(SceneFeature)
SHADER_STAGES: tuple[str, ...] = get_args(ShaderStage)

WRITE_USAGES = frozenset(
    {"color_attachment", "color_attachment_blend", "depth_attachment", "storage_write", "storage_rw",
     "transfer_dst", "accel_build"}
)
READ_ONLY_USAGES = frozenset(set(USAGES) - WRITE_USAGES)

USAGE_RESOURCE_KINDS: dict[str, frozenset[str]] = {
    "color_attachment": frozenset({"image"}),
    "color_attachment_blend": frozenset({"image"}),
    "depth_attachment": frozenset({"image"}),
    "depth_read": frozenset({"image"}),
    "sampled": frozenset({"image"}),
    "storage_read": frozenset({"image", "buffer"}),
    "storage_write": frozenset({"image", "buffer"}),
    "storage_rw": frozenset({"image", "buffer"}),
    "uniform": frozenset({"buffer"}),
    "vertex": frozenset({"buffer"}),
    "index": frozenset({"buffer"}),
    "indirect": frozenset({"buffer"}),
    "transfer_src": frozenset({"image", "buffer"}),
    "transfer_dst": frozenset({"image", "buffer"}),
    "accel_build": frozenset({"accel"}),
    "accel_read": frozenset({"accel"}),
}

# Which pass kinds may use a usage (attachments only in raster passes, and so on).
USAGE_PASS_KINDS: dict[str, frozenset[str]] = {
    "color_attachment": frozenset({"raster"}),
    "color_attachment_blend": frozenset({"raster"}),
    "depth_attachment": frozenset({"raster"}),
    "depth_read": frozenset({"raster"}),
    "vertex": frozenset({"raster"}),
    "index": frozenset({"raster"}),
    "transfer_src": frozenset({"transfer"}),
    "transfer_dst": frozenset({"transfer"}),
    "accel_build": frozenset({"compute"}),
    "sampled": frozenset({"raster", "compute", "raytrace"}),
    "storage_read": frozenset({"raster", "compute", "raytrace"}),
    "storage_write": frozenset({"raster", "compute", "raytrace"}),
    "storage_rw": frozenset({"raster", "compute", "raytrace"}),
    "uniform": frozenset({"raster", "compute", "raytrace"}),
    "indirect": frozenset({"raster", "compute", "raytrace"}),
    "accel_read": frozenset({"raster", "compute", "raytrace"}),
}

# Queues able to run each pass kind.
QUEUE_PASS_KINDS: dict[str, frozenset[str]] = {
    "graphics": frozenset(PASS_KINDS),
    "compute": frozenset({"compute", "transfer", "raytrace"}),
    "transfer": frozenset({"transfer"}),
}
