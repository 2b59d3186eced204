"""Bytes the runtime stages through host buffers: initial fills, copy regions, inputs."""

from __future__ import annotations

from typing import Any

from rgraph import formats
from rgraph.probe.semantics import mip_extent, subresources
from rgraph.probe.values import HEADER_WORDS, codec, has_header, header_words
from rgraph.vk import names
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.texels import encode


def texel_bytes(format_name: str, w: int, h: int) -> int:
    info = formats.lookup(format_name)
    bw, bh = info.block_extent[0], info.block_extent[1]
    return -(-w // bw) * -(-h // bh) * info.block_bytes


def fill_bytes(resource: dict, value: int | None, sub_list: list, plan_size: tuple[int, int]) -> bytes:
    """Staging contents that make ``sub_list`` of ``resource`` hold ``value`` (zeros if unknown)."""
    import numpy as np

    if resource["kind"] == "buffer":
        n = int(resource["size_bytes"] or resource["bytes"]) // 4
        words = np.full(n, value or 0, dtype=np.uint32)
        if has_header(resource):
            words[:HEADER_WORDS] = header_words(plan_size)
        return words.tobytes() + b"\0" * (int(resource["size_bytes"] or resource["bytes"]) - 4 * n)
    c = codec(resource["format"])
    out = []
    for mip, _layer in sub_list:
        w, h = mip_extent(resource, mip)
        if c is None or value is None:
            out.append(b"\0" * texel_bytes(resource["format"], w, h))
        else:
            out.append(c.encode(value) * (w * h))
    return b"".join(out)


def image_copy_regions(resource: dict, access: dict, buffer_offset: int = 0) -> tuple[list[Any], int]:
    """VkBufferImageCopy per (mip, layer) of an access range, tightly packed in subresources() order."""
    v = vk()
    aspect = names.aspect_mask(resource["format"])
    if formats.lookup(resource["format"]).has_depth:
        aspect = v.VK_IMAGE_ASPECT_DEPTH_BIT
    regions, offset = [], buffer_offset
    for mip, layer in subresources(access):
        w, h = mip_extent(resource, mip)
        regions.append(v.VkBufferImageCopy(
            bufferOffset=offset, bufferRowLength=0, bufferImageHeight=0,
            imageSubresource=v.VkImageSubresourceLayers(aspectMask=aspect, mipLevel=mip, baseArrayLayer=layer,
                                                        layerCount=1),
            imageOffset=v.VkOffset3D(x=0, y=0, z=0), imageExtent=v.VkExtent3D(width=w, height=h, depth=1)))
        offset += texel_bytes(resource["format"], w, h)
    return regions, offset - buffer_offset


def input_bytes(res: dict, value: Any, expected: int) -> bytes:
    """Bytes for an ``inputs`` entry: raw bytes, or an array of shader-visible values (images:
    (h, w, c) or (layers, h, w, c) for mip 0 only, when the image has one mip)."""
    import numpy as np

    if isinstance(value, (bytes, bytearray)):
        data = bytes(value)
    elif res["kind"] == "image":
        arr = np.asarray(value)
        if res["mips"] != 1:
            raise ExecutionError(f"input {res['name']!r}: arrays fill single-mip images only; give raw bytes")
        layers = arr if arr.ndim == 4 else arr[None]
        data = b"".join(encode(res["format"], layer) for layer in layers)
    else:
        data = np.asarray(value).tobytes()
    if len(data) != expected:
        raise ExecutionError(f"input {res['name']!r}: {len(data)} bytes given, the resource holds {expected}")
    return data
