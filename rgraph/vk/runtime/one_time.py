"""One-time submits: persistent/imported resources' initial contents, frame 0's releases,
and the helper that records, submits and waits for a one-time command buffer."""

from __future__ import annotations

from typing import Any

from rgraph.probe.semantics import subresources
from rgraph.probe.values import initial_value, modulus
from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.loader import vk
from rgraph.vk.record import BarrierBatch, barrier_batches
from rgraph.vk.resources import HostBuffer
from rgraph.vk.runtime.setup import FRAMES_IN_FLIGHT, pool
from rgraph.vk.runtime.staging import fill_bytes, image_copy_regions, input_bytes


def submit_once(ex: Any, queue: str, record) -> None:
    """Record (``record(cb)``), submit and wait for a one-time command buffer on plan queue ``queue``."""
    from rgraph.vk.device_local import submit_and_wait

    dev = ex.device
    submit_and_wait(dev, pool(ex, dev.families[queue], FRAMES_IN_FLIGHT), queue, record)  # a separate pool


def init_shared(ex: Any) -> None:
    """Fill persistent/imported resources with their initial value (or ``ex.inputs``), then
    move them to their ``final`` state."""
    v = vk()
    plan_size = tuple(ex.plan.get("size") or (64, 64))
    by_queue: dict[str, list] = {}
    handoffs: dict[str, list] = {}  # final queue -> images initialised on graphics
    for r in ex.resources.shared():
        if r.plan["kind"] == "accel":  # built by rgraph.vk.accel.AccelSet
            continue
        queue = r.plan["final"]["queue"]
        if _needs_graphics_copy(r, ex.device, queue):
            handoffs.setdefault(queue, []).append(r)
            queue = "graphics"
        by_queue.setdefault(queue, []).append(r)
    for queue, items in by_queue.items():
        work = []
        for r in items:
            res = r.plan
            m = modulus(res)
            value = initial_value(res["name"], m) if m else None
            if r.is_image:
                whole = {"subresource": {"mips": [0, res["mips"]], "layers": [0, res["layers"]]}}
                data = fill_bytes(res, value, subresources(whole), plan_size)
                regions = image_copy_regions(res, whole)[0]
            else:
                data = fill_bytes(res, value, [None], plan_size)
                regions = None
            if res["name"] in ex.inputs:
                data = input_bytes(res, ex.inputs[res["name"]], len(data))
            buf = HostBuffer.create(ex.device, len(data), v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
            buf.write(data)
            ex.host_buffers.append(buf)
            work.append((r, buf, regions))

        def record(cb, work=work, queue=queue):
            keep = []
            for r, buf, regions in work:
                final = r.plan["final"]
                if r.is_image:
                    rng = whole_range(r)
                    keep.append(image_barrier(cb, r, rng, (0, 0), copy_write(), v.VK_IMAGE_LAYOUT_UNDEFINED,
                                              v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL))
                    v.vkCmdCopyBufferToImage(cb, buf.handle, r.handle, v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                             len(regions), regions)
                    if final["queue"] != queue:  # release to the final queue's family
                        keep.append(_ownership_barrier(cb, r, rng, ex.device, "graphics", final["queue"], True))
                    else:
                        keep.append(image_barrier(cb, r, rng, copy_write(), _any_access(),
                                                  v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                                  names.layout(final["layout"])))
                else:
                    size = int(r.plan["size_bytes"] or r.plan["bytes"])
                    v.vkCmdCopyBuffer(cb, buf.handle, r.handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0,
                                                                                  size=size)])
                    keep.append(buffer_barrier(cb, r, copy_write(), _any_access()))

        submit_once(ex, queue, record)
    for queue, items in handoffs.items():
        submit_once(ex, queue, lambda cb, items=items, queue=queue: _acquire_initialised(cb, items, ex.device, queue))


def release_for_first_frame(ex: Any) -> None:
    """The ownership releases that frame 0's acquires pair with (``Recording.first_frame``,
    ``rgraph.vk.lower.batches.first_frame_releases``), recorded once after initialisation."""
    for queue, calls in ex.recording.first_frame.items():
        batches = barrier_batches(ex.resources, 0, calls)
        ex.log.context = f"releasing persistent resources for frame 0 on {queue}"
        submit_once(ex, queue, lambda cb, batches=batches: record_barriers(cb, batches))


def record_barriers(cb: Any, batches: list[BarrierBatch]) -> None:
    for b in batches:
        vk().vkCmdPipelineBarrier2(cb, b.dependency)


def _needs_graphics_copy(r: Any, device: Device, queue: str) -> bool:
    """Depth/stencil images can only be copied to on a graphics-capable queue family
    (VUID-vkCmdCopyBufferToImage-commandBuffer-07739): initialise them there and hand them over."""
    v = vk()
    return (r.is_image and names.aspect_mask(r.plan["format"]) != v.VK_IMAGE_ASPECT_COLOR_BIT
            and not device.same_family(queue, "graphics"))


def whole_range(r: Any) -> Any:
    return vk().VkImageSubresourceRange(aspectMask=names.aspect_mask(r.plan["format"]), baseMipLevel=0,
                                        levelCount=r.plan["mips"], baseArrayLayer=0, layerCount=r.plan["layers"])


def image_barrier(cb: Any, r: Any, rng: Any, src: tuple[int, int], dst: tuple[int, int], old_layout: int,
                  new_layout: int, families: tuple[int, int] | None = None) -> tuple:
    """Record one image barrier (``src``/``dst``: (stage mask, access mask); ``families``: an
    ownership transfer's (src, dst) queue families, else IGNORED); the structs to keep alive."""
    v = vk()
    src_family, dst_family = families or (v.VK_QUEUE_FAMILY_IGNORED, v.VK_QUEUE_FAMILY_IGNORED)
    b = v.VkImageMemoryBarrier2(srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1],
                                oldLayout=old_layout, newLayout=new_layout, srcQueueFamilyIndex=src_family,
                                dstQueueFamilyIndex=dst_family, image=r.handle, subresourceRange=rng)
    dep = v.VkDependencyInfo(imageMemoryBarrierCount=1, pImageMemoryBarriers=[b])
    v.vkCmdPipelineBarrier2(cb, dep)
    return b, dep


def buffer_barrier(cb: Any, r: Any, src: tuple[int, int], dst: tuple[int, int]) -> tuple:
    """Record one whole-buffer barrier (``src``/``dst``: (stage mask, access mask))."""
    v = vk()
    b = v.VkBufferMemoryBarrier2(srcStageMask=src[0], srcAccessMask=src[1], dstStageMask=dst[0], dstAccessMask=dst[1],
                                 srcQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED,
                                 dstQueueFamilyIndex=v.VK_QUEUE_FAMILY_IGNORED,
                                 buffer=r.handle, offset=0, size=names.WHOLE_SIZE)
    dep = v.VkDependencyInfo(bufferMemoryBarrierCount=1, pBufferMemoryBarriers=[b])
    v.vkCmdPipelineBarrier2(cb, dep)
    return b, dep


def copy_write() -> tuple[int, int]:
    v = vk()
    return v.VK_PIPELINE_STAGE_2_COPY_BIT, v.VK_ACCESS_2_TRANSFER_WRITE_BIT


def _any_access() -> tuple[int, int]:
    v = vk()
    return v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, v.VK_ACCESS_2_MEMORY_READ_BIT | v.VK_ACCESS_2_MEMORY_WRITE_BIT


def _ownership_barrier(cb: Any, r: Any, rng: Any, device: Device, src: str, dst: str, release: bool) -> tuple:
    """The release (on ``src``) or acquire (on ``dst``) half of an ownership transfer of an
    initialised image, layout kept at TRANSFER_DST_OPTIMAL; returns the structs to keep alive."""
    layout = vk().VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL
    return image_barrier(cb, r, rng, copy_write() if release else (0, 0), (0, 0) if release else _any_access(),
                         layout, layout, (device.families[src], device.families[dst]))


def _acquire_initialised(cb: Any, items: list, device: Device, queue: str) -> list:
    """On ``queue``: acquire images initialised on graphics, then move them to their final layout."""
    v = vk()
    keep: list = []
    for r in items:
        rng = whole_range(r)
        keep.append(_ownership_barrier(cb, r, rng, device, "graphics", queue, False))
        keep.append(image_barrier(cb, r, rng, (v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0), _any_access(),
                                  v.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, names.layout(r.plan["final"]["layout"])))
    return keep
