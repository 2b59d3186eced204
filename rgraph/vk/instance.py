"""The Vulkan instance: API 1.3, optional Khronos validation with synchronization validation.

Validation messages are collected (never printed from the callback) with the debug-utils
labels active when they were raised; the executor labels each pass, so a message names it.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from typing import Any

from rgraph.vk.bundled_layer import point_loader_at_bundled_layer
from rgraph.vk.errors import INSTALL_HINT, ExecutionError, VulkanUnavailable
from rgraph.vk.loader import vk

_PASS_IN_TEXT = re.compile(r"\[pass (\S+) \(set \d+\)\]")

VALIDATION_LAYER = "VK_LAYER_KHRONOS_validation"

#: Layer settings through the environment (read at load time). Layer 1.3.239 runs submit-time
#: synchronization checks only when enabled this way; 1.4 layers run them by default.
VALIDATION_ENV = {
    "VK_LAYER_ENABLES": (
        "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT:"
        "VALIDATION_CHECK_ENABLE_SYNCHRONIZATION_VALIDATION_QUEUE_SUBMIT"
    ),
    "VK_LAYER_DUPLICATE_MESSAGE_LIMIT": "1000",
    # layers since 1.3.290 validate shader (descriptor) accesses only with this heuristic on; 1.3.239
    # always did, by descriptor type. Off, a dropped barrier between two dispatches goes unseen.
    "VK_KHRONOS_VALIDATION_SYNCVAL_SHADER_ACCESSES_HEURISTIC": "true",
}

#: ``RGRAPH_GPU_AV=1`` with validation: GPU-assisted validation (shader instrumentation:
#: out-of-bounds descriptor accesses, indirect draw and dispatch arguments) instead of
#: synchronization validation (layer 1.3.239: VK_LAYER_ENABLES and VkValidationFeaturesEXT).
GPU_AV_ENABLES = ("VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_EXT:"
                  "VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_RESERVE_BINDING_SLOT_EXT")


def submit_per_pass(validate: bool) -> bool:
    """One command buffer and one vkQueueSubmit2 per pass: under validation (messages name
    their pass), or asked for with ``RGRAPH_SUBMIT_PER_PASS=1`` (a validated run's submission
    without the layer: tells a layer-timing effect from a submission-structure one)."""
    return validate or os.environ.get("RGRAPH_SUBMIT_PER_PASS", "") not in ("", "0")


def batch_cuts() -> str:
    """Where the lowering cuts batches (``rgraph.vk.lower.batches.BATCH_CUTS``): ``queue``
    (default), or ``plan`` with ``RGRAPH_BATCH_CUTS=plan`` (the cuts before session 11: an
    A/B switch for the submit's cost)."""
    cuts = os.environ.get("RGRAPH_BATCH_CUTS", "") or "queue"
    if cuts not in ("queue", "plan"):
        raise ExecutionError(f"RGRAPH_BATCH_CUTS must be queue or plan, not {cuts!r}")
    return cuts


def gpu_assisted() -> bool:
    """GPU-assisted validation asked for (environment ``RGRAPH_GPU_AV=1``)."""
    return os.environ.get("RGRAPH_GPU_AV", "") not in ("", "0")


@dataclass(frozen=True)
class ValidationMessage:
    """One message from the validation layer."""

    severity: str  # "error" | "warning"
    id_name: str
    text: str
    labels: tuple[str, ...]  # debug-utils labels (innermost last): the pass, when recorded
    context: str  # what the runtime was doing (e.g. "submit frame 1")

    @property
    def pass_name(self) -> str | None:
        """The pass: from debug labels, else the command buffer name (``pass NAME (set N)``), else
        the runtime context (``recording pass NAME``)."""
        for label in reversed(self.labels):
            if label.startswith("pass "):
                return label.removeprefix("pass ")
        found = _PASS_IN_TEXT.search(self.text)
        if found:
            return found.group(1)
        if self.context.startswith("recording pass "):
            return self.context.removeprefix("recording pass ")
        return None

    def __str__(self) -> str:
        where = self.pass_name or self.context or "?"
        return f"[{self.severity}] ({where}) {self.id_name}: {self.text}"


@dataclass
class MessageLog:
    """Collects validation messages; ``context`` is set by the runtime as it goes."""

    messages: list[ValidationMessage] = field(default_factory=list)
    context: str = ""


@dataclass
class Instance:
    """A VkInstance with its (optional) debug messenger."""

    handle: Any
    validate: bool
    log: MessageLog
    messenger: Any = None
    _callback: Any = None  # keep the Python callback alive
    _destroy_messenger: Any = None

    def proc(self, name: str) -> Any:
        return vk().vkGetInstanceProcAddr(self.handle, name)

    def destroy(self) -> None:
        v = vk()
        if self.messenger is not None:
            self._destroy_messenger(self.handle, self.messenger, None)
            self.messenger = None
        if self.handle is not None:
            v.vkDestroyInstance(self.handle, None)
            self.handle = None


def _severity_name(bits: int) -> str:
    v = vk()
    if bits & v.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT:
        return "error"
    if bits & v.VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT:
        return "warning"
    return "info"


def _make_callback(log: MessageLog):
    v = vk()
    ffi = v.ffi

    def callback(severity: int, types: int, data: Any, user: Any) -> int:
        text = ffi.string(data.pMessage).decode(errors="replace") if data.pMessage else ""
        id_name = ffi.string(data.pMessageIdName).decode(errors="replace") if data.pMessageIdName else ""
        labels = tuple(
            ffi.string(data.pCmdBufLabels[i].pLabelName).decode(errors="replace")
            for i in range(data.cmdBufLabelCount)
            if data.pCmdBufLabels[i].pLabelName
        )
        log.messages.append(ValidationMessage(_severity_name(severity), id_name, text, labels, log.context))
        return 0

    return callback


def available_layers() -> set[str]:
    point_loader_at_bundled_layer()
    v = vk()
    return {p.layerName for p in v.vkEnumerateInstanceLayerProperties()}


def create_instance(validate: bool, app_name: str = "rgraph") -> Instance:
    """Create a Vulkan 1.3 instance; with ``validate`` enable Khronos validation + syncval."""
    v = vk()
    log = MessageLog()
    layers: list[str] = []
    extensions: list[str] = []
    available_ext = {e.extensionName for e in v.vkEnumerateInstanceExtensionProperties(None)}
    if validate:
        if VALIDATION_LAYER not in available_layers():
            raise VulkanUnavailable(
                f"--validate needs {VALIDATION_LAYER}; install it with `apt-get install vulkan-validationlayers`"
            )
        os.environ.update(VALIDATION_ENV)
        if gpu_assisted():
            os.environ["VK_LAYER_ENABLES"] = GPU_AV_ENABLES
        layers.append(VALIDATION_LAYER)
    if "VK_EXT_debug_utils" in available_ext:
        extensions.append("VK_EXT_debug_utils")
    app = v.VkApplicationInfo(
        pApplicationName=app_name, applicationVersion=1, pEngineName="rgraph", engineVersion=1,
        apiVersion=v.VK_MAKE_VERSION(1, 3, 0),
    )
    enables = ([v.VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_EXT,
                v.VK_VALIDATION_FEATURE_ENABLE_GPU_ASSISTED_RESERVE_BINDING_SLOT_EXT] if gpu_assisted()
               else [v.VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT])
    features = (
        v.VkValidationFeaturesEXT(enabledValidationFeatureCount=len(enables), pEnabledValidationFeatures=enables)
        if validate else None
    )
    info = v.VkInstanceCreateInfo(
        pNext=features, pApplicationInfo=app,
        enabledLayerCount=len(layers), ppEnabledLayerNames=layers,
        enabledExtensionCount=len(extensions), ppEnabledExtensionNames=extensions,
    )
    try:
        handle = v.vkCreateInstance(info, None)
    except v.VkError as exc:
        raise VulkanUnavailable(f"vkCreateInstance failed ({type(exc).__name__}); {INSTALL_HINT}") from exc
    instance = Instance(handle=handle, validate=validate, log=log)
    if "VK_EXT_debug_utils" in extensions:
        callback = _make_callback(log)
        severity = v.VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | v.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT
        kinds = (
            v.VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | v.VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT
            | v.VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT
        )
        messenger_info = v.VkDebugUtilsMessengerCreateInfoEXT(
            messageSeverity=severity, messageType=kinds, pfnUserCallback=callback,
        )
        create = instance.proc("vkCreateDebugUtilsMessengerEXT")
        instance._destroy_messenger = instance.proc("vkDestroyDebugUtilsMessengerEXT")
        instance.messenger = create(handle, messenger_info, None)
        instance._callback = callback
    return instance


def validation_layer_version() -> tuple[int, int, int] | None:
    """The Khronos validation layer's spec version (the venv's, else the system's), or None."""
    point_loader_at_bundled_layer()
    v = vk()
    for p in v.vkEnumerateInstanceLayerProperties():
        if p.layerName == VALIDATION_LAYER:
            s = p.specVersion
            return (s >> 22, (s >> 12) & 0x3FF, s & 0xFFF)
    return None


def validation_summary(count: int) -> str:
    """The closing line of a validated run: the message count and the layer that checked."""
    version = validation_layer_version()
    layer = f" (Khronos validation layer {'.'.join(map(str, version))})" if version else ""
    return f"rgraph: {count} validation message(s){layer}"
