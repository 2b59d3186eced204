"""Aliasing hand-offs that Khronos validation 1.3.239 sees only in part.

Synchronization validation places an optimal-tiling image in its memory as if tightly packed
from the binding offset: per mip, per aspect, texel size x extent x layers, one after another
(``ImageRangeEncoder`` in the layer's subresource_adapter.cpp); samples count once. Drivers pad
images (NVIDIA: an 8x8 RGBA8 image with two mips takes 2,048 bytes, packed 320), so a
hand-off barrier on the new occupant covers, in the layer's model, fewer bytes than the plan's
hand-off takes over, and bytes of the previous occupant beyond that packed range keep its
accesses with no barrier. A later occupant of those bytes is then reported against them (H100
fuzz: random graph 1289/37 aliased, WRITE_AFTER_WRITE against an attachment write two
occupants back, ``write_barriers: 0``; 1080/32, 1337/40 and 333/36 alike).

Where that happens the runtime records, with the hand-off, a global VkMemoryBarrier2 with the
hand-off's src scope and dst ALL_COMMANDS / MEMORY_READ|MEMORY_WRITE
(``global_after`` below): the previous occupant's accesses are then ordered before
everything after, in the layer's model and on the device (where the image barrier already
ordered them before the new occupant; the global one adds only that later commands wait too).
"""

from __future__ import annotations

from rgraph import formats
from rgraph.vk.lower.context import BarrierContext
from rgraph.vk.lower.model import BarrierSpec
from rgraph.vk.lower.workarounds.after_reads import alias_names

#: dst scope of the global barrier that completes a partly seen hand-off: every later command.
GLOBAL_DST_STAGES = ("ALL_COMMANDS",)
GLOBAL_DST_ACCESS = ("MEMORY_READ", "MEMORY_WRITE")


def packed_bytes(resource: dict) -> int:
    """The bytes the layer assigns to a plan resource (buffers: their size)."""
    if resource["kind"] != "image":
        return int(resource.get("size_bytes") or resource["bytes"])
    info = formats.lookup(resource["format"])
    texel_bytes = [info.block_bytes]
    if info.has_depth and info.has_stencil:  # one range per aspect: depth (16 -> 2, 24 or 32 -> 4), stencil 1
        depth_bits = next(bits for name, bits, _kind in info.components if name == "D")
        texel_bytes = [2 if depth_bits <= 16 else 4, 1]
    bw, bh, bd = (list(info.block_extent) + [1, 1, 1])[:3]
    width, height, depth = (list(resource["extent"]) + [1, 1])[:3]
    total = 0
    for mip in range(int(resource.get("mips") or 1)):
        w, h, d = max(1, width >> mip), max(1, height >> mip), max(1, depth >> mip)
        blocks = -(-w // bw) * -(-h // bh) * -(-d // bd)
        total += sum(blocks * t for t in texel_bytes) * int(resource.get("layers") or 1)
    return total


def _span(resource: dict, size: int) -> tuple[int, int]:
    return int(resource["offset"]), int(resource["offset"]) + size


def partial_handoffs(plan: dict) -> list[set[int]]:
    """Per pass, the indices of barriers that hand memory over from previous occupants
    (``aliases``) whose packed range, within the bytes the new occupant takes over, reaches
    beyond the new occupant's packed range."""
    resources = {r["name"]: r for r in plan["resources"]}
    out: list[set[int]] = []
    for p in plan["passes"]:
        found: set[int] = set()
        for index, b in enumerate(p["barriers"]):
            new = resources.get(b["resource"])
            if not b.get("aliases") or new is None or new.get("offset") is None:
                continue
            real = _span(new, int(new["bytes"]))
            packed = _span(new, packed_bytes(new))
            for name in alias_names(b["aliases"]):
                old = resources.get(name)
                if old is None or old.get("heap") != new.get("heap") or old.get("offset") is None:
                    continue
                start, end = _span(old, packed_bytes(old))
                start, end = max(start, real[0]), min(end, real[1])  # the part this hand-off takes over
                if start < end and (start < packed[0] or end > packed[1]):
                    found.add(index)
        out.append(found)
    return out


def global_after(spec: BarrierSpec, ctx: BarrierContext) -> list[BarrierSpec]:
    """A partly seen hand-off (``ctx.partial_handoff``) is followed, in the same call, by a
    global memory barrier with its src scope, ordering it before every later command."""
    if ctx.partial_handoff and ctx.group == 0 and spec.src_stages:
        return [spec, BarrierSpec(None, None, spec.src_stages, spec.src_access, GLOBAL_DST_STAGES,
                                  GLOBAL_DST_ACCESS, None, None)]
    return [spec]
