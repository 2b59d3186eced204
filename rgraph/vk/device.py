"""Physical device choice, the logical device, plan queues and their timeline semaphores."""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from typing import Any

from rgraph.vk.errors import INSTALL_HINT, VulkanUnavailable
from rgraph.vk.instance import Instance, gpu_assisted
from rgraph.vk.loader import vk

PLAN_QUEUES = ("graphics", "compute", "transfer")

#: Vulkan 1.2/1.3 features the runtime cannot do without.
REQUIRED_12 = ("timelineSemaphore", "separateDepthStencilLayouts", "hostQueryReset")
REQUIRED_13 = ("synchronization2", "maintenance4")
#: Core features the probe uses when a plan needs them (enabled when present).
OPTIONAL_CORE = (
    "fragmentStoresAndAtomics", "vertexPipelineStoresAndAtomics", "shaderStorageImageWriteWithoutFormat",
    "shaderStorageImageReadWithoutFormat", "drawIndirectFirstInstance", "multiDrawIndirect", "independentBlend",
    "shaderFloat64",  # float64 transform variants (the large-world study)
    "geometryShader",  # gl_PrimitiveID in fragment shaders (the hybrid's visibility buffer)
    "shaderInt64",  # 64-bit integers (the hybrid's wavefront accumulators, passes/raytrace_wave.py)
)


@dataclass
class PhysicalDeviceInfo:
    index: int
    handle: Any
    name: str
    device_type: str  # "discrete" | "integrated" | "cpu" | "virtual" | "other"
    api_version: tuple[int, int, int]


def _type_name(device_type: int) -> str:
    v = vk()
    return {
        v.VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: "discrete",
        v.VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: "integrated",
        v.VK_PHYSICAL_DEVICE_TYPE_CPU: "cpu",
        v.VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: "virtual",
    }.get(device_type, "other")


def list_physical_devices(instance: Instance) -> list[PhysicalDeviceInfo]:
    v = vk()
    try:
        handles = v.vkEnumeratePhysicalDevices(instance.handle)
    except v.VkError:
        handles = []
    out = []
    for i, h in enumerate(handles):
        p = v.vkGetPhysicalDeviceProperties(h)
        api = p.apiVersion
        out.append(PhysicalDeviceInfo(
            i, h, v.ffi.string(p.deviceName).decode() if not isinstance(p.deviceName, str) else p.deviceName,
            _type_name(p.deviceType), (api >> 22, (api >> 12) & 0x3FF, api & 0xFFF),
        ))
    return out


def choose_physical_device(devices: list[PhysicalDeviceInfo], index: int | None) -> PhysicalDeviceInfo:
    """``index`` if given; else the first discrete GPU, else lavapipe (cpu), else the first."""
    if not devices:
        raise VulkanUnavailable(f"no Vulkan device found; {INSTALL_HINT}")
    if index is not None:
        if not 0 <= index < len(devices):
            names = ", ".join(f"{d.index}: {d.name}" for d in devices)
            raise VulkanUnavailable(f"device index {index} (--device / --devices) is out of range; devices are {names}")
        return devices[index]
    usable = [d for d in devices if d.api_version >= (1, 3, 0)] or devices
    for kind in ("discrete", "cpu", "integrated"):
        for d in usable:
            if d.device_type == kind:
                return d
    return usable[0]


@dataclass
class Device:
    """A logical device with one VkQueue per plan queue; owns the timeline semaphores made by
    ``new_timeline`` (destroyed with it)."""

    instance: Instance
    physical: PhysicalDeviceInfo
    handle: Any
    families: dict[str, int]  # plan queue -> queue family index
    queues: dict[str, Any]  # plan queue -> VkQueue (shared when families coincide)
    timelines: list[Any] = field(default_factory=list)
    properties: Any = None
    memory_properties: Any = None
    enabled_features: set[str] = field(default_factory=set)
    timestamp_period_ns: float = 1.0
    timestamp_valid_bits: dict[str, int] = field(default_factory=dict)
    capabilities: dict[str, frozenset[str]] = field(default_factory=dict)  # plan queue -> graphics/compute/transfer
    _fns: dict[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.physical.name

    @property
    def fence_timeout_ns(self) -> int:
        """How long a fence wait may take before it fails with VK_TIMEOUT: 100 s, 30 minutes under
        validation (GPU-assisted validation on lavapipe spent 115 s in the first frame of
        rt_hybrid_raster with a cold shader cache); ``RGRAPH_FENCE_TIMEOUT_S`` overrides both."""
        override = os.environ.get("RGRAPH_FENCE_TIMEOUT_S", "")
        seconds = float(override) if override else (1800.0 if self.instance.validate else 100.0)
        return int(seconds * 1e9)

    def fn(self, name: str) -> Any:
        """An extension command (debug-utils labels) through the instance."""
        if name not in self._fns:
            try:
                self._fns[name] = self.instance.proc(name)
            except Exception:  # noqa: BLE001 -- extension absent: labels are optional
                self._fns[name] = None
        return self._fns[name]

    def same_family(self, a: str, b: str) -> bool:
        return self.families[a] == self.families[b]

    def same_queue(self, a: str, b: str) -> bool:
        return self.queues[a] == self.queues[b]

    def new_timeline(self) -> Any:
        """A timeline semaphore at value 0, destroyed with the device."""
        self.timelines.append(create_timeline(self, 0))
        return self.timelines[-1]

    def wait_idle(self) -> None:
        vk().vkDeviceWaitIdle(self.handle)

    def destroy(self) -> None:
        v = vk()
        if self.handle is None:
            return
        wait_idle_for_teardown(self.handle)
        for sem in self.timelines:
            v.vkDestroySemaphore(self.handle, sem, None)
        self.timelines.clear()
        v.vkDestroyDevice(self.handle, None)
        self.handle = None


def wait_idle_for_teardown(handle: Any) -> None:
    """vkDeviceWaitIdle before destroying objects; a lost device is idle for that purpose
    (objects of a lost device may still be destroyed), so the error that lost it, already
    raised, is what the user sees rather than a second one from the teardown."""
    v = vk()
    try:
        v.vkDeviceWaitIdle(handle)
    except v.VkErrorDeviceLost:
        pass


def _family_for(families: list[Any], queue: str) -> int:
    v = vk()
    g, c, t = v.VK_QUEUE_GRAPHICS_BIT, v.VK_QUEUE_COMPUTE_BIT, v.VK_QUEUE_TRANSFER_BIT
    graphics = next((i for i, f in enumerate(families) if f.queueFlags & g and f.queueFlags & c), None)
    if graphics is None:
        raise VulkanUnavailable("the device has no graphics+compute queue family")
    if queue == "compute":
        for i, f in enumerate(families):
            if f.queueFlags & c and not f.queueFlags & g:
                return i
    if queue == "transfer":
        for i, f in enumerate(families):
            if f.queueFlags & t and not f.queueFlags & (g | c):
                return i
    return graphics


def _query_features(handle: Any) -> tuple[Any, Any, Any, Any]:
    """(features2, Vulkan 1.2, (Vulkan 1.1, Vulkan 1.3) features, core features) of a physical device."""
    v = vk()
    f13 = v.VkPhysicalDeviceVulkan13Features()
    f11 = v.VkPhysicalDeviceVulkan11Features(pNext=f13)
    f12 = v.VkPhysicalDeviceVulkan12Features(pNext=f11)
    f2 = v.VkPhysicalDeviceFeatures2(pNext=f12)
    v.vkGetPhysicalDeviceFeatures2(handle, f2)
    return f2, f12, (f11, f13), f2.features


#: Vulkan 1.2 features GPU-assisted validation's shader instrumentation uses (layer 1.4.309)
GPU_AV_FEATURES_12 = ("vulkanMemoryModel", "vulkanMemoryModelDeviceScope", "uniformAndStorageBuffer8BitAccess")

#: enabled whenever offered: the shared host allocation between devices (rgraph.vk.multi.host_memory)
OPTIONAL_EXTENSIONS = ("VK_EXT_external_memory_host",)


def offered_extensions(physical: Any) -> set[str]:
    """The device extensions a physical device offers."""
    v = vk()
    return {p.extensionName if isinstance(p.extensionName, str) else v.ffi.string(p.extensionName).decode()
            for p in v.vkEnumerateDeviceExtensionProperties(physical, None)}


def create_device(instance: Instance, device_index: int | None = None, verbose: bool = True,
                  ray_tracing: bool = False, one_queue: bool = False) -> Device:
    """Choose a physical device, check required features, create the queues. ``ray_tracing``
    enables acceleration structures, ray tracing pipelines and buffer device addresses
    (``rgraph.vk.rt_device``). ``one_queue``: every plan queue on the graphics+compute family's
    one VkQueue (no async compute: one vkQueueSubmit2 per frame, no cross-queue semaphores)."""
    v = vk()
    physical = choose_physical_device(list_physical_devices(instance), device_index)
    if physical.api_version < (1, 3, 0):
        raise VulkanUnavailable(f"{physical.name} supports Vulkan {physical.api_version}; rgraph needs 1.3")
    if verbose:
        print(f"rgraph: device {physical.index}: {physical.name} ({physical.device_type})", file=sys.stderr)
    _f2, f12, (f11, f13), core = _query_features(physical.handle)
    missing = [n for n in REQUIRED_12 if not getattr(f12, n)] + [n for n in REQUIRED_13 if not getattr(f13, n)]
    if missing:
        raise VulkanUnavailable(f"{physical.name} lacks required Vulkan features: {', '.join(missing)}")
    families = v.vkGetPhysicalDeviceQueueFamilyProperties(physical.handle)
    plan_families = {q: _family_for(families, "graphics" if one_queue else q) for q in PLAN_QUEUES}
    distinct = sorted(set(plan_families.values()))
    priorities = [1.0]
    queue_infos = [
        v.VkDeviceQueueCreateInfo(queueFamilyIndex=fam, queueCount=1, pQueuePriorities=priorities)
        for fam in distinct
    ]
    enabled_core = {n for n in OPTIONAL_CORE if getattr(core, n)}
    int64_atomics = bool(f12.shaderBufferInt64Atomics) and "shaderInt64" in enabled_core
    core_features = v.VkPhysicalDeviceFeatures(**{n: v.VK_TRUE for n in enabled_core})
    e13 = v.VkPhysicalDeviceVulkan13Features(synchronization2=v.VK_TRUE, maintenance4=v.VK_TRUE)
    multiview = bool(f11.multiview)  # Vulkan 1.1 (VK_KHR_multiview, core)
    e11 = v.VkPhysicalDeviceVulkan11Features(pNext=e13, multiview=v.VK_TRUE if multiview else v.VK_FALSE)
    e12 = v.VkPhysicalDeviceVulkan12Features(
        pNext=e11, drawIndirectCount=v.VK_TRUE if f12.drawIndirectCount else v.VK_FALSE, timelineSemaphore=v.VK_TRUE, separateDepthStencilLayouts=v.VK_TRUE,
        hostQueryReset=v.VK_TRUE,  # timestamp queries are reset from the host (transfer queues cannot)
        shaderOutputLayer=v.VK_TRUE if f12.shaderOutputLayer else v.VK_FALSE,  # gl_Layer in vertex shaders
        bufferDeviceAddress=v.VK_TRUE if ray_tracing else v.VK_FALSE,
        shaderBufferInt64Atomics=v.VK_TRUE if int64_atomics else v.VK_FALSE,
    )
    if instance.validate and gpu_assisted():  # what GPU-assisted validation's instrumentation needs
        for name in GPU_AV_FEATURES_12:  # (the layer would force them on, with a warning each)
            setattr(e12, name, getattr(f12, name))
    extensions: list[str] = []
    head: Any = e12
    if ray_tracing:
        from rgraph.vk import rt_device

        head, extensions = rt_device.chain(physical.handle, physical.name, e12)
    extensions = extensions + [e for e in OPTIONAL_EXTENSIONS if e in offered_extensions(physical.handle)]
    enabled = v.VkPhysicalDeviceFeatures2(pNext=head, features=core_features)
    info = v.VkDeviceCreateInfo(
        pNext=enabled, queueCreateInfoCount=len(queue_infos), pQueueCreateInfos=queue_infos,
        enabledExtensionCount=len(extensions), ppEnabledExtensionNames=extensions,
    )
    handle = v.vkCreateDevice(physical.handle, info, None)
    queues_by_family = {fam: v.vkGetDeviceQueue(handle, fam, 0) for fam in distinct}
    props = v.vkGetPhysicalDeviceProperties(physical.handle)
    device = Device(
        instance=instance, physical=physical, handle=handle, families=plan_families,
        queues={q: queues_by_family[f] for q, f in plan_families.items()},
        properties=props, memory_properties=v.vkGetPhysicalDeviceMemoryProperties(physical.handle),
        enabled_features=enabled_core | set(REQUIRED_12) | set(REQUIRED_13)
        | ({"shaderOutputLayer"} if f12.shaderOutputLayer else set())
        | ({"drawIndirectCount"} if f12.drawIndirectCount else set()) | ({"multiview"} if multiview else set())
        | ({"shaderBufferInt64Atomics"} if int64_atomics else set())
        | ({"bufferDeviceAddress", "accelerationStructure", "rayTracingPipeline"} if ray_tracing else set())
        | ({"rayQuery"} if "VK_KHR_ray_query" in extensions else set()),
        timestamp_period_ns=float(props.limits.timestampPeriod),
        timestamp_valid_bits={q: families[f].timestampValidBits for q, f in plan_families.items()},
        capabilities={q: _capabilities(families[f].queueFlags) for q, f in plan_families.items()},
    )
    device.__dict__["extensions"] = tuple(extensions)
    return device


def _capabilities(flags: int) -> frozenset[str]:
    v = vk()
    return frozenset(name for name, bit in (("graphics", v.VK_QUEUE_GRAPHICS_BIT), ("compute", v.VK_QUEUE_COMPUTE_BIT),
                                            ("transfer", v.VK_QUEUE_TRANSFER_BIT)) if flags & bit)


def create_timeline(device: Device, initial: int) -> Any:
    v = vk()
    type_info = v.VkSemaphoreTypeCreateInfo(semaphoreType=v.VK_SEMAPHORE_TYPE_TIMELINE, initialValue=initial)
    return v.vkCreateSemaphore(device.handle, v.VkSemaphoreCreateInfo(pNext=type_info), None)
