"""How scene geometry is drawn (graph param ``draw.mode``) and the shader defines that follow.

- ``cpu`` (default): per frame the CPU writes every draw's camera-relative matrix (float64
  subtraction, float32 upload) and records one instanced draw per mesh (the original path).
- ``gpu``: persistent per-instance data (``shaders/scene/scene.glsl`` ``Instance``; float64
  translations with ``shaderFloat64``, a float32 high/low split otherwise), culled on the GPU
  (``draw_cull``) into indirect commands and a count drawn by ``vkCmdDrawIndexedIndirectCount``;
  the CPU does no per-object work per frame.
- ``naive`` (``rgraph run --naive-cpu``): the engines' way - per frame the CPU tests every
  object against the frustum, writes its matrix, and the frame's command buffers are
  recorded again with one draw call per visible object (param ``draw.naive``:
  ``rgraph.vk.scene_naive``).

Param ``views`` (1 or 2): stereo with VK_KHR_multiview (``RGRAPH_VIEWS``); ``views.ipd`` metres.
"""

from __future__ import annotations

from typing import Any

from rgraph.vk.errors import ExecutionError

MODES = ("cpu", "gpu", "naive")
MAX_VIEWS = 2


def draw_mode(plan: dict) -> str:
    mode = str(plan.get("params", {}).get("draw.mode", "cpu"))
    if mode not in MODES:
        raise ExecutionError(f"draw.mode must be one of {', '.join(MODES)}, got {mode!r}")
    return mode


NAIVE_WAYS = ("direct", "indirect")


def naive_way(plan: dict) -> str:
    """How draw.mode=naive draws (param ``draw.naive``, ``rgraph.vk.scene_naive``): ``direct``
    (default: the draws of the visible objects recorded per frame) or ``indirect``."""
    way = str(plan.get("params", {}).get("draw.naive", "direct"))
    if way not in NAIVE_WAYS:
        raise ExecutionError(f"draw.naive must be one of {', '.join(NAIVE_WAYS)}, got {way!r}")
    return way


def view_count(plan: dict) -> int:
    views = int(plan.get("params", {}).get("views", 1))
    if not 1 <= views <= MAX_VIEWS:
        raise ExecutionError(f"views must be 1 or {MAX_VIEWS}, got {views}")
    return views


def use_float64(plan: dict, device: Any) -> bool:
    """float64 instance translations: draw.mode=gpu on a device with shaderFloat64 (param
    ``draw.float64`` false forces the float32 high/low path)."""
    wanted = str(plan.get("params", {}).get("draw.float64", "true")).lower() not in ("false", "0", "no")
    return draw_mode(plan) == "gpu" and wanted and "shaderFloat64" in device.enabled_features


def scene_defines(plan: dict, device: Any) -> dict[str, int]:
    """Defines every shader of a scene plan is compiled with (none for the default cpu mono path)."""
    if not plan.get("scene_source"):
        return {}
    out: dict[str, int] = {}
    if draw_mode(plan) == "gpu":
        out["SCENE_INSTANCES"] = 1
        if use_float64(plan, device):
            out["SCENE_FLOAT64"] = 1
    views = view_count(plan)
    if views > 1:
        if "multiview" not in device.enabled_features:
            raise ExecutionError("views=2 needs the Vulkan 1.1 feature multiview (VK_KHR_multiview); the device lacks it")
        out["RGRAPH_VIEWS"] = views
    return out
