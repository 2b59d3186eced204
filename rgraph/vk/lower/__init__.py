"""Pure lowering: a plan and a queue-family layout -> the ``Recording`` the runtime records.

No Vulkan and no device: ``rgraph inspect PLAN --lowered`` prints it, tests check it, and
``rgraph.vk.record`` turns its barrier calls into sync2 structs. Validation-layer 1.3.239
workarounds live in ``rgraph.vk.lower.workarounds`` and can be switched off.
"""

from rgraph.vk.lower.lower import LoweringError, lower
from rgraph.vk.lower.model import BarrierCall, BarrierSpec, Batch, PassRecording, Recording, SemaphoreEdge
from rgraph.vk.lower.queues import QueueLayout, from_device, separate_families, single_family
from rgraph.vk.lower.workarounds import LAYER_WORKAROUNDS

__all__ = ["LAYER_WORKAROUNDS", "BarrierCall", "BarrierSpec", "Batch", "LoweringError", "PassRecording",
           "QueueLayout", "Recording", "SemaphoreEdge", "from_device", "lower", "separate_families", "single_family"]
