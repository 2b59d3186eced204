"""Prebuilt submit arrays per frame-in-flight set; per frame only the semaphore values change.

Each batch is one VkSubmitInfo2 (its semaphores order it against the other queues).
Batches go in the recording's ``order`` (each VkQueue runs ahead as far as its waits allow;
every wait is submitted after its signal). Under validation each batch is its own
vkQueueSubmit2 call so that messages name the batch. Without validation each VkQueue gets
one call per frame with all its batches (``one_call_per_queue``, the default: a wait may
then be submitted before its signal, which timeline semaphores allow, and the driver's
per-call cost is paid once per queue), or, with it off, one call per run of consecutive
batches on one VkQueue in submission order. Semaphores: one per edge of the recording
(``rgraph.vk.lower.semaphores``), value = frame + offset, written straight into the cffi
structs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rgraph.vk import names
from rgraph.vk.instance import submit_per_pass
from rgraph.vk.loader import vk
from rgraph.vk.lower.semaphores import batch_semaphores, semaphore_count
from rgraph.vk.runtime.setup import FRAMES_IN_FLIGHT


@dataclass
class SubmitCall:
    """One vkQueueSubmit2 of a frame: ``count`` prebuilt VkSubmitInfo2 in ``infos``."""

    queue: Any
    count: int
    infos: Any
    fence: Any  # VkFence or ffi.NULL
    context: str  # for validation messages
    keep: list[Any]  # cffi arrays the infos point into


def build(ex: Any) -> None:
    v = vk()
    ffi = v.ffi
    dev = ex.device
    recording = ex.recording
    batches = recording.batches
    plan_passes = ex.plan["passes"]
    edges = list(recording.edges)
    ex.layer_edges = recording.layer_edges
    semaphores = [dev.new_timeline() for _ in range(semaphore_count(edges, FRAMES_IN_FLIGHT))]
    ex.semaphores = semaphores
    family = dev.families
    last_of: dict[int, int] = {}
    for bi, batch in enumerate(batches):
        last_of[family[batch.queue]] = bi
    fence_batches = sorted(set(last_of.values()))
    runs: list[list[int]] = []
    if submit_per_pass(ex.instance.validate):
        runs = [[bi] for bi in recording.order]
    elif ex.one_call_per_queue:  # waits may come before their signals: timeline semantics allow it
        per_queue: dict[int, list[int]] = {}
        for bi in recording.order:
            per_queue.setdefault(family[batches[bi].queue], []).append(bi)
        runs = list(per_queue.values())
    else:
        for bi in recording.order:
            if runs and family[batches[runs[-1][-1]].queue] == family[batches[bi].queue]:
                runs[-1].append(bi)
            else:
                runs.append([bi])
    ex.fences = [[v.vkCreateFence(dev.handle, v.VkFenceCreateInfo(flags=v.VK_FENCE_CREATE_SIGNALED_BIT), None)
                  for _ in fence_batches] for _ in range(FRAMES_IN_FLIGHT)]
    ex.fence_arrays = [ffi.new("VkFence[]", fences) if fences else ffi.NULL for fences in ex.fences]
    ex.submit_calls = []
    ex.value_slots = []
    for s in range(FRAMES_IN_FLIGHT):
        calls: list[SubmitCall] = []
        slots: list[tuple[Any, int]] = []
        for run in runs:
            infos = ffi.new("VkSubmitInfo2[]", len(run))
            keep: list[Any] = [infos]
            for j, bi in enumerate(run):
                waits, signals = batch_semaphores(edges, FRAMES_IN_FLIGHT, s, bi)
                info = infos[j]
                info.sType = v.VK_STRUCTURE_TYPE_SUBMIT_INFO_2
                for count_field, array_field, specs in (("waitSemaphoreInfoCount", "pWaitSemaphoreInfos", waits),
                                                        ("signalSemaphoreInfoCount", "pSignalSemaphoreInfos", signals)):
                    if not specs:
                        continue
                    array = ffi.new("VkSemaphoreSubmitInfo[]", len(specs))
                    keep.append(array)
                    for k, use in enumerate(specs):
                        array[k].sType = v.VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO
                        array[k].semaphore = semaphores[use.semaphore]
                        array[k].stageMask = names.stages(use.stages)
                        slots.append((array[k], use.offset))
                    setattr(info, count_field, len(specs))
                    setattr(info, array_field, array)
                cbi = ffi.new("VkCommandBufferSubmitInfo[]", 1)
                cbi[0].sType = v.VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO
                cbi[0].commandBuffer = ex.command_buffers[s][bi]
                keep.append(cbi)
                info.commandBufferInfoCount = 1
                info.pCommandBufferInfos = cbi
            fence_index = next((fence_batches.index(bi) for bi in run if bi in fence_batches), None)
            fence = ex.fences[s][fence_index] if fence_index is not None else ffi.NULL
            context = "submit of " + ", ".join(
                f"batch {bi} [{', '.join(plan_passes[i]['name'] for i in batches[bi].passes)}]" for bi in run)
            calls.append(SubmitCall(dev.queues[batches[run[0]].queue], len(run), infos, fence, context, keep))
        ex.submit_calls.append(calls)
        ex.value_slots.append(slots)
