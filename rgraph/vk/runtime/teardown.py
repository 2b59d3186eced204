"""Teardown: every object of one executor destroyed in reverse order of creation; the device
and instance too when the executor opened them (not when ``rgraph.api.Gpu`` lent them)."""

from __future__ import annotations

from typing import Any

from rgraph.vk.device import wait_idle_for_teardown
from rgraph.vk.instance import ValidationMessage
from rgraph.vk.loader import vk


def close(ex: Any) -> list[ValidationMessage]:
    v = vk()
    if getattr(ex, "logic", None) is not None:  # before the scene's memory goes away
        ex.logic.stop()
    dev = ex.device
    if dev is not None and dev.handle is not None:
        ex.log.context = "teardown"
        wait_idle_for_teardown(dev.handle)
        for fences in ex.fences:
            for f in fences:
                v.vkDestroyFence(dev.handle, f, None)
        ex.fences = []
        for pool in ex.query_pools:
            v.vkDestroyQueryPool(dev.handle, pool, None)
        ex.query_pools = []
        for pool in ex.pools.values():
            v.vkDestroyCommandPool(dev.handle, pool, None)
        ex.pools = {}
        for p in reversed(ex.passes):
            p.destroy()
        ex.passes = []
        if ex.scene_gpu is not None:
            ex.scene_gpu.destroy()
            ex.scene_gpu = None
        for sampler in ex.samplers.values():
            v.vkDestroySampler(dev.handle, sampler, None)
        ex.samplers = {}
        for buf in reversed(ex.host_buffers):
            buf.destroy()
        ex.host_buffers = []
        if ex.accels is not None:
            ex.accels.destroy()
            ex.accels = None
        if ex.resources is not None:
            ex.resources.destroy()
            ex.resources = None
        for sem in ex.semaphores:
            if sem in dev.timelines:
                dev.timelines.remove(sem)
            v.vkDestroySemaphore(dev.handle, sem, None)
        ex.semaphores = []
        if ex.owns_device:
            dev.destroy()
    if ex.owns_device and ex.instance is not None and ex.instance.handle is not None:
        ex.instance.destroy()
    return ex.log.messages
