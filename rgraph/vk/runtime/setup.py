"""Setup: resources, pass implementations, query pools and command pools of one executor."""

from __future__ import annotations

from typing import Any

from rgraph.vk.errors import ExecutionError
from rgraph.vk.impl_pass import ImplPass, overrides_update
from rgraph.vk.loader import vk
from rgraph.vk.resources import ResourceSet

FRAMES_IN_FLIGHT = 2


#: Timestamp queries past the passes' 2 per pass that no pass uses. Lavapipe (Mesa 25.0)
#: writes as many timestamps as the last render pass had views, even outside a render pass
#: (``handle_write_timestamp2`` counts ``state->info.view_mask``, which ending the pass does not
#: clear): after a multiview pass, a command buffer's later timestamps each spill into the next
#: query, and the last one past the pool, which crashed the driver (``clustered -p views=2``
#: with no pass after ``forward`` in its batch, e.g. a device's share of a split frame). The
#: spilled-into queries of later passes are reset and written again before they are read; the
#: slack covers the most views a render pass can have (a 32-bit view mask).
QUERY_SLACK = 32


def create(ex: Any) -> None:
    """Resources, initial contents, frame 0's releases, pipelines, query pools, then recording."""
    from rgraph.vk.runtime import commands, one_time, submits

    v = vk()
    dev = ex.device
    for p in ex.plan["passes"]:
        if p.get("device", 0) != 0:
            devices = ex.plan.get("multi_device", {}).get("devices", 2)
            raise ExecutionError(f"pass {p['name']!r} runs on plan device {p['device']}: run a multi-device plan "
                                 f"with one device per plan device (--devices {','.join(['0'] * devices)})")
    ex.log.context = "creating resources"
    ex.resources = ResourceSet(dev, ex.plan, FRAMES_IN_FLIGHT, external=ex.external)
    ex.log.context = "initialising persistent resources"
    one_time.init_shared(ex)
    if any(r["kind"] == "accel" for r in ex.plan["resources"]):
        from rgraph.vk.accel import AccelSet

        ex.log.context = "building persistent acceleration structures"
        ex.accels = AccelSet(dev, ex.plan, ex.resources, lambda queue, rec: one_time.submit_once(ex, queue, rec))
    one_time.release_for_first_frame(ex)
    for p in ex.plan["passes"]:
        ex.log.context = f"creating pipelines of pass {p['name']}"
        ex.passes.append(ImplPass(dev, ex.plan, p, ex.resources, sets=FRAMES_IN_FLIGHT,
                                  scene=lambda: scene(ex), samplers=ex.samplers, accels=ex.accels))
    ex.updaters = [p for p in ex.passes if overrides_update(p)]
    n = len(ex.plan["passes"])
    count = max(2 * n, 2) + QUERY_SLACK
    for _ in range(FRAMES_IN_FLIGHT):
        ex.query_pools.append(v.vkCreateQueryPool(dev.handle, v.VkQueryPoolCreateInfo(
            queryType=v.VK_QUERY_TYPE_TIMESTAMP, queryCount=count), None))
        # reset from the host (hostQueryReset): vkCmdResetQueryPool is not allowed on a
        # transfer-only queue family, and one host call per frame replaces one per pass
        v.vkResetQueryPool(dev.handle, ex.query_pools[-1], 0, count)
    ex.log.context = "recording"
    commands.record(ex)
    submits.build(ex)


def scene(ex: Any) -> Any:
    """The scene's geometry on the device (``rgraph.vk.scene_gpu``), built on first use."""
    if ex.scene_gpu is None:
        from rgraph.vk.runtime.one_time import submit_once
        from rgraph.vk.scene_gpu import SceneGPU

        context = ex.log.context
        ex.log.context = "uploading the scene"
        ex.scene_gpu = SceneGPU(ex.device, ex.plan, FRAMES_IN_FLIGHT,
                                lambda queue, record: submit_once(ex, queue, record))
        ex.log.context = context
    return ex.scene_gpu


def attach_logic(ex: Any, hz: float) -> None:
    """A logic thread at ``hz`` for the scene (``rgraph.vk.runtime.logic``; without a scene it
    ticks with nothing to compute); ``run_frames`` starts and stops it."""
    from rgraph.vk.runtime.logic import LogicThread

    try:
        scene = ex.scene_gpu
        lock = scene.lock if scene is not None else None
        ex.logic = LogicThread(scene.logic_step if scene is not None else (lambda _s: None), hz, lock=lock)
    except ValueError as exc:
        raise ExecutionError(str(exc)) from None
    if ex.scene_gpu is not None:
        ex.scene_gpu.attach_logic(ex.logic)


def pool(ex: Any, family: int, set_index: int) -> Any:
    """The command pool of ``family`` for frame-in-flight set ``set_index`` (FRAMES_IN_FLIGHT:
    one-time work), created on first use."""
    v = vk()
    key = (family, set_index)
    if key not in ex.pools:
        ex.pools[key] = v.vkCreateCommandPool(ex.device.handle, v.VkCommandPoolCreateInfo(
            queueFamilyIndex=family), None)
    return ex.pools[key]
