"""The scissor of a sort-first tile (``params["rgraph.scissor"] = [x, y, w, h]``).

The viewport stays the whole attachment, so the projection is the one-device projection
and every pixel inside the band gets exactly the value it gets on one device.
"""

from __future__ import annotations

from typing import Any

from rgraph.plan.devices import SCISSOR  # noqa: F401 (re-exported for the runtime)
from rgraph.vk.loader import vk


def scissor_rect(plan_pass: dict[str, Any], width: int, height: int) -> Any:
    """The VkRect2D a pipeline of this pass uses: its tile clamped to the attachment, else all of it."""
    v = vk()
    rect = (plan_pass.get("params") or {}).get(SCISSOR)
    if rect is None:
        return v.VkRect2D(offset=v.VkOffset2D(x=0, y=0), extent=v.VkExtent2D(width=width, height=height))
    x, y, w, h = (int(n) for n in rect)
    x0, y0 = min(max(x, 0), width), min(max(y, 0), height)
    x1, y1 = min(x + w, width), min(y + h, height)
    return v.VkRect2D(offset=v.VkOffset2D(x=x0, y=y0), extent=v.VkExtent2D(width=max(0, x1 - x0),
                                                                          height=max(0, y1 - y0)))
