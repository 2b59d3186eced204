"""Queue-family layouts a plan is lowered for: which plan queues share a family (and VkQueue)
and what each family can do. From a live device, or a model for lowering without one."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from rgraph.stages import CAPABILITIES

PLAN_QUEUES = ("graphics", "compute", "transfer")


@dataclass(frozen=True)
class QueueLayout:
    """Plan queue -> queue family index and capabilities (graphics/compute/transfer).

    The runtime creates one VkQueue per family, so plan queues of one family share a VkQueue."""

    families: Mapping[str, int]
    capabilities: Mapping[str, frozenset[str]]
    source: str = "model"

    def family(self, queue: str) -> int:
        return self.families[queue]

    def same_queue(self, a: str, b: str) -> bool:
        return self.families[a] == self.families[b]

    def same_family(self, a: str, b: str) -> bool:
        return self.families[a] == self.families[b]

    def capabilities_of(self, queue: str) -> frozenset[str]:
        return self.capabilities.get(queue, CAPABILITIES)


def single_family() -> QueueLayout:
    """One family doing graphics, compute and transfer (lavapipe; every plan queue on one VkQueue)."""
    return QueueLayout({q: 0 for q in PLAN_QUEUES}, {q: CAPABILITIES for q in PLAN_QUEUES},
                       "model: one queue family (graphics+compute+transfer), as on lavapipe")


def separate_families() -> QueueLayout:
    """Graphics+compute+transfer, compute+transfer and transfer-only families (as on NVIDIA)."""
    caps = {"graphics": CAPABILITIES, "compute": frozenset({"compute", "transfer"}),
            "transfer": frozenset({"transfer"})}
    return QueueLayout({"graphics": 0, "compute": 1, "transfer": 2}, caps,
                       "model: separate graphics, compute and transfer families, as on NVIDIA")


MODELS = {"single": single_family, "separate": separate_families}


def from_device(device) -> QueueLayout:
    """The layout of a live ``rgraph.vk.device.Device``."""
    return QueueLayout(dict(device.families), {q: device.capabilities.get(q, CAPABILITIES) for q in device.families},
                       f"device: {device.name}")
