"""Plan resources on the device: images, buffers and heaps (one VkDeviceMemory per plan heap).

Transient and output resources exist once per frame in flight ("set"); persistent and
imported ones once, in set 0's copy of their heap. Each created object's real memory
requirements are checked against the plan's ``bytes``/``alignment``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rgraph.vk import names
from rgraph.vk.debug_names import name_object, resource_name
from rgraph.vk.device import Device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.memreq import buffer_create_info, image_create_info

SHARED = ("persistent", "imported")


@dataclass
class Resource:
    plan: dict
    handle: Any
    set_index: int  # frame-in-flight set; shared resources: 0
    size: int = 0
    alignment: int = 0
    type_bits: int = 0
    views: dict[tuple, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.plan["name"]

    @property
    def is_image(self) -> bool:
        return self.plan["kind"] == "image"


def memory_type(device: Device, type_bits: int, want: int, avoid: int = 0, prefer: int = 0) -> int:
    """The first memory type allowed by ``type_bits`` with all ``want`` flags (prefers lacking
    ``avoid``, then having all ``prefer`` flags)."""
    props = device.memory_properties
    candidates = [i for i in range(props.memoryTypeCount)
                  if type_bits & (1 << i) and props.memoryTypes[i].propertyFlags & want == want]
    if not candidates:
        raise ExecutionError(f"no memory type with flags {want:#x} among bits {type_bits:#x}")
    preferred = [i for i in candidates if not props.memoryTypes[i].propertyFlags & avoid] or candidates
    flagged = [i for i in preferred if props.memoryTypes[i].propertyFlags & prefer == prefer]
    return (flagged or preferred)[0]


@dataclass
class HostBuffer:
    """A host-visible, coherent buffer with its own memory, mapped for the run's life."""

    device: Device
    handle: Any
    memory: Any
    size: int
    mapped: Any

    @classmethod
    def create(cls, device: Device, size: int, usage: int, allocate_flags: int = 0,
               readback: bool = False, device_local: bool = False) -> HostBuffer:
        """``allocate_flags``: VkMemoryAllocateFlags (e.g. device address) for its memory;
        ``readback``: the host reads it, so prefer HOST_CACHED memory (reads of uncached,
        write-combined memory run at a few hundred MB/s); ``device_local``: shaders read it
        often, so prefer DEVICE_LOCAL memory where a host-visible type has it (resizable BAR)."""
        v = vk()
        size = max(int(size), 4)
        info = v.VkBufferCreateInfo(size=size, usage=usage, sharingMode=v.VK_SHARING_MODE_EXCLUSIVE)
        handle = v.vkCreateBuffer(device.handle, info, None)
        req = v.vkGetBufferMemoryRequirements(device.handle, handle)
        want = v.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | v.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
        prefer = v.VK_MEMORY_PROPERTY_HOST_CACHED_BIT if readback else 0
        if device_local:
            prefer |= v.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT
        index = memory_type(device, req.memoryTypeBits, want, prefer=prefer)
        chain = {"pNext": v.VkMemoryAllocateFlagsInfo(flags=allocate_flags)} if allocate_flags else {}  # alive until the call returns
        memory = v.vkAllocateMemory(device.handle, v.VkMemoryAllocateInfo(
            allocationSize=req.size, memoryTypeIndex=index, **chain), None)
        v.vkBindBufferMemory(device.handle, handle, memory, 0)
        mapped = v.vkMapMemory(device.handle, memory, 0, size, 0)
        return cls(device, handle, memory, size, mapped)

    def write(self, data: bytes, offset: int = 0) -> None:
        self.mapped[offset:offset + len(data)] = data

    def read(self, size: int | None = None, offset: int = 0) -> bytes:
        return bytes(self.mapped[offset:offset + (self.size if size is None else size)])

    def destroy(self) -> None:
        v = vk()
        v.vkUnmapMemory(self.device.handle, self.memory)
        v.vkDestroyBuffer(self.device.handle, self.handle, None)
        v.vkFreeMemory(self.device.handle, self.memory, None)


def staging_buffer(ex: Any, purpose: str, name: str, size: int, usage: int) -> HostBuffer:
    """The executor ``ex``'s host buffer for ``purpose`` ("readback" or "upload") of resource
    ``name``: made on first use (readback: HOST_CACHED preferred) and reused while it is big
    enough; the caller has waited for the previous use. Destroyed with ``ex.host_buffers``."""
    key = (purpose, name)
    buf = ex.staging.get(key)
    if buf is None or buf.size < size:
        buf = HostBuffer.create(ex.device, size, usage, readback=purpose == "readback")
        ex.host_buffers.append(buf)
        ex.staging[key] = buf
    return buf


class ResourceSet:
    """Every plan resource for every frame-in-flight set, bound into per-heap memory."""

    def __init__(self, device: Device, plan: dict, sets: int, external: dict[str, list[Any]] | None = None) -> None:
        """``external``: buffers the caller created and bound (one VkBuffer per set, the
        caller destroys them), used instead of creating those plan resources: the shared host
        allocation of ``rgraph.vk.multi.host_memory``. Even a shared lifetime gets one per set."""
        self.device = device
        self.plan = plan
        self.sets = sets
        self.by_set: list[dict[str, Resource]] = [{} for _ in range(sets)]
        self.memories: list[Any] = []
        self.external = dict(external or {})
        self._create()

    def get(self, name: str, set_index: int) -> Resource:
        return self.by_set[set_index][name]

    def shared(self) -> list[Resource]:
        return [r for r in self.by_set[0].values() if r.plan["lifetime"] in SHARED]

    def _create_object(self, res: dict, alias: bool) -> Any:
        v = vk()
        if res["kind"] == "image":
            info = image_create_info(res["format"], res["extent"], res["mips"], res["layers"], res["samples"],
                                     res["usages"], alias=alias)
            return v.vkCreateImage(self.device.handle, info, None)
        if res["kind"] in ("buffer", "accel"):  # an accel: the buffer its structures live in
            info = buffer_create_info(res["size_bytes"] or res["bytes"], res["usages"])
            return v.vkCreateBuffer(self.device.handle, info, None)
        raise ExecutionError(f"resource {res['name']!r}: kind {res['kind']!r} is not supported by the runtime")

    def _create(self) -> None:
        v = vk()
        dev = self.device.handle
        heaps = {h["id"]: h for h in self.plan["heaps"]}
        members: dict[int, list[dict]] = {h: [] for h in heaps}
        for res in self.plan["resources"]:
            if res.get("heap") is None:
                raise ExecutionError(f"resource {res['name']!r} has no heap in the plan")
            if res["heap"] not in heaps:
                raise ExecutionError(f"resource {res['name']!r} names heap {res['heap']} that the plan lacks")
            if res["name"] in self.external:
                handles = self.external[res["name"]]
                if res["kind"] != "buffer" or len(handles) != self.sets:
                    raise ExecutionError(f"resource {res['name']!r}: an external buffer needs one handle per set")
                for t in range(self.sets):
                    self.by_set[t][res["name"]] = Resource(res, handles[t], t)
                continue
            members[res["heap"]].append(res)
        for heap_id, heap in sorted(heaps.items()):
            residents = members[heap_id]
            if not residents:
                continue
            per_frame = any(r["lifetime"] not in SHARED for r in residents)
            copies = self.sets if per_frame else 1
            aliased = _aliased(residents)
            for set_index in range(copies):
                created: list[Resource] = []
                for res in residents:
                    if res["lifetime"] in SHARED and set_index > 0:
                        continue
                    handle = self._create_object(res, alias=res["name"] in aliased)
                    r = Resource(res, handle, set_index)
                    name_object(self.device, handle, v.VK_OBJECT_TYPE_IMAGE if r.is_image else v.VK_OBJECT_TYPE_BUFFER,
                                resource_name(res, set_index, copies))
                    if r.is_image:
                        req = v.vkGetImageMemoryRequirements(dev, handle)
                    else:
                        req = v.vkGetBufferMemoryRequirements(dev, handle)
                    r.size, r.alignment, r.type_bits = int(req.size), int(req.alignment), int(req.memoryTypeBits)
                    self._check(res, r, heap)
                    created.append(r)
                    targets = range(self.sets) if res["lifetime"] in SHARED else [set_index]
                    for t in targets:
                        self.by_set[t][res["name"]] = r
                bits = ~0
                for r in created:
                    bits &= r.type_bits
                if bits == 0:
                    raise ExecutionError(f"heap {heap_id}: its resources share no memory type")
                index = memory_type(self.device, bits, v.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)
                flags = (v.VkMemoryAllocateFlagsInfo(flags=names.MEMORY_ALLOCATE_DEVICE_ADDRESS)
                         if any(set(r["usages"]) & names.DEVICE_ADDRESS_USAGES for r in residents) else None)
                memory = v.vkAllocateMemory(dev, v.VkMemoryAllocateInfo(pNext=flags, allocationSize=int(heap["bytes"]),
                                                                        memoryTypeIndex=index), None)
                self.memories.append(memory)
                name_object(self.device, memory, v.VK_OBJECT_TYPE_DEVICE_MEMORY,
                            f"heap {heap_id} ({heap.get('memory_class') or '?'})"
                            + (f" (frame set {set_index})" if copies > 1 else ""))
                for r in created:
                    offset = int(r.plan["offset"])
                    if r.is_image:
                        v.vkBindImageMemory(dev, r.handle, memory, offset)
                    else:
                        v.vkBindBufferMemory(dev, r.handle, memory, offset)

    @staticmethod
    def _check(res: dict, r: Resource, heap: dict) -> None:
        name = res["name"]
        if r.size != int(res["bytes"]):
            raise ExecutionError(f"resource {name!r}: the device needs {r.size} bytes, the plan says {res['bytes']}")
        if res.get("alignment") is not None and r.alignment != int(res["alignment"]):
            raise ExecutionError(
                f"resource {name!r}: the device needs alignment {r.alignment}, the plan says {res['alignment']}")
        offset = int(res["offset"])
        if offset % r.alignment:
            raise ExecutionError(f"resource {name!r}: offset {offset} is not a multiple of alignment {r.alignment}")
        if offset + r.size > int(heap["bytes"]):
            raise ExecutionError(f"resource {name!r}: [{offset}, {offset + r.size}) exceeds heap {heap['id']} "
                                 f"of {heap['bytes']} bytes")

    def view(self, r: Resource, mips: tuple[int, int], layers: tuple[int, int], aspect: int | None = None,
             array: bool = True) -> Any:
        """A view of an image range (cached): 2D-array, or 2D when ``array`` is false and one layer."""
        v = vk()
        aspect = aspect if aspect is not None else names.aspect_mask(r.plan["format"])
        array = array or layers[1] - layers[0] > 1
        key = (mips, layers, aspect, array)
        if key not in r.views:
            info = v.VkImageViewCreateInfo(
                image=r.handle, viewType=v.VK_IMAGE_VIEW_TYPE_2D_ARRAY if array else v.VK_IMAGE_VIEW_TYPE_2D,
                format=names.format_value(r.plan["format"]),
                subresourceRange=v.VkImageSubresourceRange(
                    aspectMask=aspect, baseMipLevel=mips[0], levelCount=mips[1] - mips[0],
                    baseArrayLayer=layers[0], layerCount=layers[1] - layers[0]),
            )
            r.views[key] = v.vkCreateImageView(self.device.handle, info, None)
            name_object(self.device, r.views[key], v.VK_OBJECT_TYPE_IMAGE_VIEW,
                        f"{r.plan['name']} view mips {mips[0]}:{mips[1]} layers {layers[0]}:{layers[1]}")
        return r.views[key]

    def destroy(self) -> None:
        v = vk()
        dev = self.device.handle
        seen: set[int] = set()
        for set_map in reversed(self.by_set):
            for r in set_map.values():
                if id(r) in seen:
                    continue
                seen.add(id(r))
                if r.name in self.external:
                    continue
                for view in r.views.values():
                    v.vkDestroyImageView(dev, view, None)
                if r.is_image:
                    v.vkDestroyImage(dev, r.handle, None)
                else:
                    v.vkDestroyBuffer(dev, r.handle, None)
        for memory in reversed(self.memories):
            v.vkFreeMemory(dev, memory, None)
        self.by_set = []
        self.memories = []


def destroy_owned(device: Device, objects: list[tuple[str, Any]], host_buffers: list[HostBuffer]) -> None:
    """Destroy a pass's own objects ((vkDestroy* name, handle), newest first) and host
    buffers, and empty both lists."""
    v = vk()
    for destroy, handle in reversed(objects):
        getattr(v, destroy)(device.handle, handle, None)
    objects.clear()
    for buf in reversed(host_buffers):
        buf.destroy()
    host_buffers.clear()


def _aliased(residents: list[dict]) -> set[str]:
    """Names of resources whose memory range overlaps another resident's."""
    out = set()
    spans = [(int(r["offset"]), int(r["offset"]) + int(r["bytes"]), r["name"]) for r in residents]
    for i, (a0, a1, an) in enumerate(spans):
        for b0, b1, bn in spans[i + 1:]:
            if a0 < b1 and b0 < a1:
                out.update((an, bn))
    return out
