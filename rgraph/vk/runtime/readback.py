"""Readback after the frames: bytes of every output/persistent/imported subresource, decoded."""

from __future__ import annotations

from typing import Any

from rgraph.probe.semantics import mip_extent
from rgraph.stages import CAPABILITIES, fit_to_queue
from rgraph.vk import names
from rgraph.vk.loader import vk
from rgraph.vk.resources import staging_buffer
from rgraph.vk.runtime.one_time import buffer_barrier, image_barrier, submit_once, whole_range
from rgraph.vk.runtime.setup import FRAMES_IN_FLIGHT
from rgraph.vk.runtime.staging import image_copy_regions, texel_bytes
from rgraph.vk.texels import decode

READ_LIFETIMES = ("output", "persistent", "imported")


def read_back(ex: Any, frames: int | None = None) -> dict[tuple, bytes]:
    """(resource, mip, layer) -> bytes ((name, None, None) for buffers) after the last frame
    (``frames``: frames run so far, default the executor's count)."""
    v = vk()
    done = ex.frames_done if frames is None else frames
    s = (done - 1) % FRAMES_IN_FLIGHT
    out: dict[tuple, bytes] = {}
    wanted = [r for r in ex.plan["resources"] if r["lifetime"] in READ_LIFETIMES and r.get("first") is not None
              and r["kind"] != "accel"]  # accels: checked through the rays traced against them
    by_queue: dict[str, list[dict]] = {}
    for res in wanted:
        by_queue.setdefault(res["final"]["queue"], []).append(res)
    for queue, items in by_queue.items():
        jobs = []
        for res in items:
            r = ex.resources.get(res["name"], s)
            if r.is_image:
                whole = {"subresource": {"mips": [0, res["mips"]], "layers": [0, res["layers"]]}}
                regions, size = image_copy_regions(res, whole)
            else:
                regions, size = None, int(res["size_bytes"] or res["bytes"])
            buf = staging_buffer(ex, "readback", res["name"], size, v.VK_BUFFER_USAGE_TRANSFER_DST_BIT)
            jobs.append((res, r, buf, regions, size))

        capabilities = ex.device.capabilities.get(queue, CAPABILITIES)

        def record(cb, jobs=jobs, capabilities=capabilities):
            keep = []
            for res, r, buf, regions, size in jobs:
                # the final state may name stages of another family (a graphics read of a
                # resource whose last queue is compute: INDEX_INPUT, H100 fuzz seed 32/32)
                stages, access = fit_to_queue(res["final"]["stages"], res["final"]["access"], capabilities)
                src = names.stages(stages), names.accesses(access)
                copy_read = v.VK_PIPELINE_STAGE_2_COPY_BIT, v.VK_ACCESS_2_TRANSFER_READ_BIT
                if r.is_image:
                    keep.append(image_barrier(cb, r, whole_range(r), src, copy_read,
                                              names.layout(res["final"]["layout"]),
                                              v.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL))
                    v.vkCmdCopyImageToBuffer(cb, r.handle, v.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buf.handle,
                                             len(regions), regions)
                else:
                    keep.append(buffer_barrier(cb, r, src, copy_read))
                    v.vkCmdCopyBuffer(cb, r.handle, buf.handle, 1, [v.VkBufferCopy(srcOffset=0, dstOffset=0,
                                                                                  size=size)])

        ex.log.context = "readback"
        submit_once(ex, queue, record)
        for res, _r, buf, _regions, size in jobs:
            data = buf.read(size)
            if res["kind"] == "image":
                offset = 0
                for mip in range(res["mips"]):
                    w, h = mip_extent(res, mip)
                    n = texel_bytes(res["format"], w, h)
                    for layer in range(res["layers"]):
                        out[(res["name"], mip, layer)] = data[offset:offset + n]
                        offset += n
            else:
                out[(res["name"], None, None)] = data
    return out


def decode_outputs(plan: dict, data: dict[tuple, bytes]) -> dict[str, Any]:
    """Read-back bytes -> shader-visible arrays per resource: images (h, w, c) float32
    ((layers, h, w, c) when layered; mip 0), buffers uint8."""
    import numpy as np

    out: dict[str, Any] = {}
    for res in plan["resources"]:
        if res["kind"] == "image" and (res["name"], 0, 0) in data:
            w, h = mip_extent(res, 0)
            try:
                layers = [decode(res["format"], data[(res["name"], 0, layer)], w, h) for layer in range(res["layers"])]
            except ValueError:
                continue
            out[res["name"]] = layers[0] if len(layers) == 1 else np.stack(layers)
        elif (res["name"], None, None) in data:
            out[res["name"]] = np.frombuffer(data[(res["name"], None, None)], dtype=np.uint8)
    return out
