"""The copy passes of multi-device plans (the compiler's multi-device transformation): a band or whole
image into a buffer on the sending device, and a buffer into the band on the receiving one.

``params.rect = [x, y, w, h]`` is the region (mip 0, every layer of the access), packed
row-major layer after layer, so both ends agree on the bytes without further metadata.
"""

from __future__ import annotations

from typing import Any

from rgraph import formats
from rgraph.impl import PassImpl, register
from rgraph.plan.devices import DOWNLOAD_IMPL, UPLOAD_IMPL
from rgraph.vk import names
from rgraph.vk.loader import vk


def band_regions(setup: Any, image: str) -> list[Any]:
    """One VkBufferImageCopy per layer of ``image``'s access for the pass's ``rect``."""
    v = vk()
    x, y, w, h = (int(n) for n in setup.param("rect"))
    plan = setup.resource_plan(image)
    info = formats.lookup(plan["format"])
    aspect = v.VK_IMAGE_ASPECT_DEPTH_BIT if info.has_depth else names.aspect_mask(plan["format"])
    texel = info.block_bytes
    layers = setup.access(image)["subresource"]["layers"]
    out = []
    for n, layer in enumerate(range(*layers)):
        out.append(v.VkBufferImageCopy(
            bufferOffset=n * w * h * texel, bufferRowLength=0, bufferImageHeight=0,
            imageSubresource=v.VkImageSubresourceLayers(aspectMask=aspect, mipLevel=0, baseArrayLayer=layer,
                                                        layerCount=1),
            imageOffset=v.VkOffset3D(x=x, y=y, z=0), imageExtent=v.VkExtent3D(width=w, height=h, depth=1)))
    return out


def _image_and_buffer(setup: Any) -> tuple[str, str]:
    accesses = setup.plan_pass["accesses"]
    image = next(a["resource"] for a in accesses if a["subresource"] is not None)
    buffer = next(a["resource"] for a in accesses if a["subresource"] is None)
    return image, buffer


class _BandCopy(PassImpl):
    """The image and buffer a copy pass names, and the regions of its ``rect``."""

    def __init__(self, setup: Any) -> None:
        super().__init__(setup)
        self.image, self.buffer = _image_and_buffer(setup)
        self.regions = band_regions(setup, self.image)
        self.layout = names.layout(setup.access(self.image)["layout"])


@register(DOWNLOAD_IMPL)
class Download(_BandCopy):
    """Device ``d > 0``: the band (or whole image) into the tile buffer (read back to the host after the frame)."""

    def record(self, rec: Any, frame_set: int) -> None:
        img = self.setup.resource(self.image, frame_set)
        buf, _size = self.setup.buffer(self.buffer, frame_set)
        rec.copy_image_to_buffer(img.handle, self.layout, buf, self.regions)
        rec.make_available_to_host(buf)  # the shared host allocation: the receiver reads it after the fence


@register(UPLOAD_IMPL)
class Upload(_BandCopy):
    """Device 0: the received buffer into place (sort-first: the composite itself)."""

    def record(self, rec: Any, frame_set: int) -> None:
        img = self.setup.resource(self.image, frame_set)
        buf, _size = self.setup.buffer(self.buffer, frame_set)
        rec.copy_buffer_to_image(buf, img.handle, self.layout, self.regions)
