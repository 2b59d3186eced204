"""Acceleration structures on the device: one BLAS per mesh and one TLAS per plan accel, placed
in the plan's accel buffer at the offsets the compiler chose (the compiler's accel sizing phase).

Geometry inputs (vertices, indices, instances) are runtime-owned host-visible buffers with
device addresses. A build records every BLAS build in one call, a memory dependency of the
build itself (BLAS written -> TLAS build reads them; the scratch reused) and the TLAS build:
that dependency is internal to the one ``accel_build`` access the plan synchronizes.
Persistent accels are built once at load (BLAS with compaction into the plan's buffer); when
the plan marks them ``refit`` every frame's build updates them in place. Accels over a scene
with deformable meshes that are built every frame (refit, or per-frame lifetimes) read their
vertices from ``rgraph.vk.rt_deform.DeformedTables`` (per set, the frame's deformed geometry;
a refit updates only the deformable meshes' BLAS, then the TLAS).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rgraph.vk import names
from rgraph.vk.accel_sizes import build_flags, instances_geometry, query, triangles_geometry
from rgraph.vk.device import Device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.resources import SHARED, HostBuffer, ResourceSet
from rgraph.vk.rt_device import device_address, proc

INPUT_USAGE = 0x80000 | names.SHADER_DEVICE_ADDRESS  # ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY
INSTANCE_BYTES = 64


@dataclass
class Geometry:
    """What one accel holds: meshes (float32 positions (n, 3), uint32 indices (m, 3)) and
    instances (3x4 float32 transform, mesh index, custom index)."""

    meshes: list[tuple[np.ndarray, np.ndarray]]
    instances: list[tuple[np.ndarray, int, int]]


def probe_geometry(value: int) -> Geometry:
    """The probe's test geometry (PROBE_BLAS of the compiler's accel sizing): a quad [-1, 1]^2 at
    z = 0, instanced at the origin (custom index ``value``) and at x = 3 (``value + 1``)."""
    quad = np.array([[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0]], dtype=np.float32)
    idx = np.array([[0, 1, 2], [2, 1, 3]], dtype=np.uint32)
    eye = np.eye(3, 4, dtype=np.float32)
    moved = eye.copy()
    moved[0, 3] = 3.0
    return Geometry([(quad, idx)], [(eye, 0, value), (moved, 0, value + 1)])


def pack_instances(instances: list[tuple[np.ndarray, int, int]], blas_addresses: list[int]) -> bytes:
    """VkAccelerationStructureInstanceKHR records (mask 0xFF, SBT offset 0, culling off)."""
    out = []
    flags = 0x1  # VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR
    for transform, mesh, custom in instances:
        out.append(np.asarray(transform, dtype=np.float32).reshape(12).tobytes()
                   + struct.pack("<IIQ", (custom & 0xFFFFFF) | (0xFF << 24), flags << 24, blas_addresses[mesh]))
    return b"".join(out)


def buffer_address(device: Device, buffer: Any) -> int:
    v = vk()
    return device_address(device, "vkGetBufferDeviceAddress", v.VkBufferDeviceAddressInfo(buffer=buffer))


@dataclass
class AddressBuffer:
    """A host-visible buffer with a device address (geometry inputs, instances, SBTs, scratch)."""

    host: HostBuffer
    address: int

    @classmethod
    def create(cls, device: Device, size: int, usage: int, device_local: bool = False) -> AddressBuffer:
        host = HostBuffer.create(device, max(int(size), 16), usage | names.SHADER_DEVICE_ADDRESS,
                                 allocate_flags=names.MEMORY_ALLOCATE_DEVICE_ADDRESS, device_local=device_local)
        return cls(host, buffer_address(device, host.handle))

    def destroy(self) -> None:
        self.host.destroy()


@dataclass
class BuiltAccel:
    """One plan accel in one frame-in-flight set: its structures and build structs."""

    blas: list[Any]
    tlas: Any
    instances: AddressBuffer
    keep: list[Any] = field(default_factory=list)


class AccelSet:
    """Every accel of a plan, per set; records builds and refits."""

    def __init__(self, device: Device, plan: dict, resources: ResourceSet, one_time) -> None:
        self.device = device
        self.plan = plan
        self.resources = resources
        self.buffers: list[AddressBuffer] = []
        self.built: dict[tuple[str, int], BuiltAccel] = {}
        self.layouts: dict[str, dict] = {}
        self.compacted: dict[str, list[int]] = {}  # persistent accels: each BLAS's compacted bytes
        self.inputs: dict[str, tuple[Geometry, list[tuple[int, int]]]] = {}
        self.deformed: Any = None  # rgraph.vk.rt_deform.DeformedTables (see the module docstring)
        self.deforming: set[str] = set()  # accels whose builds read it
        for res in plan["resources"]:
            if res["kind"] != "accel":
                continue
            self.layouts[res["name"]] = res["accel"]
            self._create(res)
            if res["lifetime"] in SHARED and res["accel"]["refit"]:
                one_time("compute", lambda cb, name=res["name"]: self._initial_build(cb, name))
            elif res["lifetime"] in SHARED:
                self._compacted_build(res["name"], one_time)

    # ------------------------------------------------------------------ setup
    def geometry(self, res: dict) -> Geometry:
        from rgraph.probe.semantics import accel_value

        layout = res["accel"]
        if layout["geometry"] == "probe":
            return probe_geometry(accel_value(self.plan, res["name"]))
        from rgraph.vk.rt_scene import scene_geometry

        return scene_geometry(self.plan)

    def _create(self, res: dict) -> None:
        v = vk()
        layout = res["accel"]
        geo = self.geometry(res)
        if len(geo.meshes) != len(layout["blas"]) or len(geo.instances) != layout["tlas"]["instances"]:
            raise ExecutionError(f"accel {res['name']!r}: the plan's geometry differs from the scene's "
                                 "(recompile the plan for this scene)")
        ranges = []
        data = bytearray()
        for positions, indices in geo.meshes:
            vo = len(data)
            data += np.ascontiguousarray(positions, dtype=np.float32).tobytes()
            data += b"\0" * (-len(data) % 16)
            io = len(data)
            data += np.ascontiguousarray(indices, dtype=np.uint32).tobytes()
            data += b"\0" * (-len(data) % 16)
            ranges.append((vo, io))
        inputs = AddressBuffer.create(self.device, len(data), INPUT_USAGE)
        inputs.host.write(bytes(data))
        self.buffers.append(inputs)
        self.inputs[res["name"]] = (geo, [(inputs.address + vo, inputs.address + io) for vo, io in ranges])
        per_frame = res["lifetime"] not in SHARED or layout["refit"]
        if layout["geometry"] == "scene" and per_frame:
            self._use_deformed(res["name"])
        create = proc(self.device, "vkCreateAccelerationStructureKHR")
        sets = 1 if res["lifetime"] in SHARED else self.resources.sets
        for s in range(sets):
            buf = self.resources.get(res["name"], s)
            blas = [create(self.device.handle, v.VkAccelerationStructureCreateInfoKHR(
                buffer=buf.handle, offset=b["offset"], size=b["bytes"],
                type=v.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR), None) for b in layout["blas"]]
            tlas = create(self.device.handle, v.VkAccelerationStructureCreateInfoKHR(
                buffer=buf.handle, offset=layout["tlas"]["offset"], size=layout["tlas"]["bytes"],
                type=v.VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR), None)
            addresses = [self._address(b) for b in blas]
            instances = AddressBuffer.create(self.device, INSTANCE_BYTES * len(geo.instances), INPUT_USAGE)
            instances.host.write(pack_instances(geo.instances, addresses))
            self.buffers.append(instances)
            built = BuiltAccel(blas, tlas, instances)
            for t in (range(self.resources.sets) if res["lifetime"] in SHARED else [s]):
                self.built[(res["name"], t)] = built

    def _use_deformed(self, name: str) -> None:
        """Accel ``name`` is built every frame: over a scene with deformable meshes, from the
        frame's deformed geometry."""
        from rgraph.vk.rt_deform import DeformedTables, has_deformable

        if self.deformed is None:
            if not has_deformable(self.plan):
                return
            self.deformed = DeformedTables(self.device, self.plan, self.resources.sets)
        self.deforming.add(name)

    def update(self, frame: int, frame_set: int) -> None:
        """Before frame ``frame``'s submits (its set's previous frame has finished): the
        deformed geometry of set ``frame_set`` (nothing without deformable meshes)."""
        if self.deformed is not None:
            self.deformed.update(frame, frame_set)

    def _address(self, accel: Any) -> int:
        v = vk()
        return device_address(self.device, "vkGetAccelerationStructureDeviceAddressKHR",
                              v.VkAccelerationStructureDeviceAddressInfoKHR(accelerationStructure=accel))

    def tlas(self, name: str, set_index: int) -> Any:
        return self.built[(name, set_index)].tlas

    def _compacted_build(self, name: str, one_time) -> None:
        """Build-once accels: BLAS built with ALLOW_COMPACTION in a temporary buffer, compacted
        into the plan's buffer at the plan's offsets (compacted <= built size), then the TLAS."""
        v = vk()
        layout = self.layouts[name]
        built = self.built[(name, 0)]
        geo, addresses = self.inputs[name]
        align = int(layout["scratch_alignment"])
        sizes = [query(self.device, "bottom", b["triangles"], b["max_vertex"], compact=True) for b in layout["blas"]]
        offsets, total = [], 0
        for size, _, _ in sizes:
            offsets.append(total)
            total = -(-(total + size) // 256) * 256
        temp = AddressBuffer.create(self.device, total, 0x100000)  # ACCELERATION_STRUCTURE_STORAGE
        scratch_bytes = sum(-(-s[1] // align) * align for s in sizes)
        tlas_scratch = query(self.device, "top", layout["tlas"]["instances"], 0)[1]
        scratch = AddressBuffer.create(self.device, max(scratch_bytes, tlas_scratch) + align, 0x20)
        self.buffers += [temp, scratch]
        scratch_address = -(-scratch.address // align) * align
        create = proc(self.device, "vkCreateAccelerationStructureKHR")
        destroy = proc(self.device, "vkDestroyAccelerationStructureKHR")
        temps = [create(self.device.handle, v.VkAccelerationStructureCreateInfoKHR(
            buffer=temp.host.handle, offset=o, size=s[0], type=v.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR), None)
            for o, s in zip(offsets, sizes, strict=True)]
        pool = v.vkCreateQueryPool(self.device.handle, v.VkQueryPoolCreateInfo(
            queryType=v.VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, queryCount=len(temps)), None)
        v.vkResetQueryPool(self.device.handle, pool, 0, len(temps))
        fn = proc(self.device, "vkCmdBuildAccelerationStructuresKHR")

        def build(cb: Any) -> None:
            infos, keep, offset = [], [], 0
            for i, ((positions, _), (va, ia)) in enumerate(zip(geo.meshes, addresses, strict=True)):
                geometry = v.ffi.new("VkAccelerationStructureGeometryKHR[1]",
                                     [triangles_geometry(va, ia, len(positions) - 1)])
                keep.append(geometry)
                infos.append(v.VkAccelerationStructureBuildGeometryInfoKHR(
                    type=v.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, flags=build_flags(False, True),
                    mode=v.VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR, dstAccelerationStructure=temps[i],
                    geometryCount=1, pGeometries=geometry,
                    scratchData=v.VkDeviceOrHostAddressKHR(deviceAddress=scratch_address + offset)))
                offset += -(-sizes[i][1] // align) * align
            self._build(fn, cb, infos, [len(m[1]) for m in geo.meshes], keep)
            self._build_barrier(cb)
            handles = v.ffi.new("VkAccelerationStructureKHR[]", temps)
            proc(self.device, "vkCmdWriteAccelerationStructuresPropertiesKHR")(
                cb, len(temps), handles, v.VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, pool, 0)

        one_time("compute", build)
        results = v.ffi.new("uint64_t[]", len(temps))
        v.vkGetQueryPoolResults(self.device.handle, pool, 0, len(temps), 8 * len(temps), results, 8,
                                v.VK_QUERY_RESULT_64_BIT | v.VK_QUERY_RESULT_WAIT_BIT)
        v.vkDestroyQueryPool(self.device.handle, pool, None)
        compacted = [int(results[i]) for i in range(len(temps))]
        res_buf = self.resources.get(name, 0)
        for i, b in enumerate(layout["blas"]):  # the plan's BLAS objects, now of their compacted size
            if compacted[i] > b["bytes"]:
                raise ExecutionError(f"accel {name!r}: compacted BLAS {i} ({compacted[i]} bytes) exceeds its "
                                     f"plan size {b['bytes']}")
            destroy(self.device.handle, built.blas[i], None)
            built.blas[i] = create(self.device.handle, v.VkAccelerationStructureCreateInfoKHR(
                buffer=res_buf.handle, offset=b["offset"], size=compacted[i],
                type=v.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR), None)
        built.instances.host.write(pack_instances(geo.instances, [self._address(h) for h in built.blas]))
        self.compacted[name] = compacted

        def compact(cb: Any) -> None:
            copy = proc(self.device, "vkCmdCopyAccelerationStructureKHR")
            infos = [v.VkCopyAccelerationStructureInfoKHR(src=t, dst=d, mode=v.VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR)
                     for t, d in zip(temps, built.blas, strict=True)]
            for info in infos:
                copy(cb, info)
            self._build_barrier(cb)
            geometry = v.ffi.new("VkAccelerationStructureGeometryKHR[1]", [instances_geometry(built.instances.address)])
            tlas = v.VkAccelerationStructureBuildGeometryInfoKHR(
                type=v.VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, flags=build_flags(False, False),
                mode=v.VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR, dstAccelerationStructure=built.tlas,
                geometryCount=1, pGeometries=geometry,
                scratchData=v.VkDeviceOrHostAddressKHR(deviceAddress=scratch_address))
            self._build(fn, cb, [tlas], [len(geo.instances)], [geometry, infos])

        one_time("compute", compact)
        for t in temps:
            destroy(self.device.handle, t, None)

    def _build_barrier(self, cb: Any) -> None:
        """Inside a build: structures written -> read by the next build/copy, scratch reused.
        Copies (compaction) run in the build stage: the copy stage is VK_KHR_ray_tracing_maintenance1's,
        which the device does not enable."""
        v = vk()
        barrier = v.VkMemoryBarrier2(
            srcStageMask=v.VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
            srcAccessMask=v.VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR,
            dstStageMask=v.VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR,
            dstAccessMask=(v.VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR
                           | v.VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR))
        dependency = v.VkDependencyInfo(memoryBarrierCount=1, pMemoryBarriers=[barrier])
        v.vkCmdPipelineBarrier2(cb, dependency)

    # ------------------------------------------------------------------ record
    def _initial_build(self, cb: Any, name: str) -> None:
        layout = self.layouts[name]
        sizes = [query(self.device, "bottom", b["triangles"], b["max_vertex"], layout["refit"])[1]
                 for b in layout["blas"]]
        align = int(layout["scratch_alignment"])
        total = sum(-(-s // align) * align for s in sizes)
        total = max(total, query(self.device, "top", layout["tlas"]["instances"], 0, layout["refit"])[1])
        scratch = AddressBuffer.create(self.device, total + align, 0x20)  # STORAGE_BUFFER
        self.buffers.append(scratch)
        self.record_build(cb, name, 0, -(-scratch.address // align) * align, update=False)

    def record_build(self, cb: Any, name: str, set_index: int, scratch_address: int, update: bool) -> None:
        """All BLAS, an internal build->build dependency, then the TLAS (``update``: refit)."""
        v = vk()
        layout = self.layouts[name]
        built = self.built[(name, set_index)]
        geo, addresses = self.inputs[name]
        refit = bool(layout["refit"])
        mode = v.VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR if update else v.VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR
        align = int(layout["scratch_alignment"])
        fn = proc(self.device, "vkCmdBuildAccelerationStructuresKHR")
        deformed = self.deformed if name in self.deforming else None
        infos, ranges, keep, offset = [], [], [], 0
        for i, ((positions, indices), (va, ia), b) in enumerate(zip(geo.meshes, addresses, layout["blas"], strict=True)):
            sizes = query(self.device, "bottom", b["triangles"], b["max_vertex"], refit)
            step = -(-(sizes[2] if update else sizes[1]) // align) * align
            if deformed is not None:
                if update and not deformed.is_deformable(i):  # a static mesh's BLAS stays valid
                    offset += step
                    continue
                va = deformed.vertex_address(i, set_index)
            geometry = v.ffi.new("VkAccelerationStructureGeometryKHR[1]", [triangles_geometry(va, ia, len(positions) - 1)])
            keep.append(geometry)
            infos.append(v.VkAccelerationStructureBuildGeometryInfoKHR(
                type=v.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, flags=build_flags(refit, False), mode=mode,
                srcAccelerationStructure=built.blas[i] if update else None, dstAccelerationStructure=built.blas[i],
                geometryCount=1, pGeometries=geometry,
                scratchData=v.VkDeviceOrHostAddressKHR(deviceAddress=scratch_address + offset)))
            offset += step
            ranges.append(len(indices))
        if infos:
            self._build(fn, cb, infos, ranges, keep)
        self._build_barrier(cb)  # inside the build: BLAS -> TLAS, scratch reuse
        geometry = v.ffi.new("VkAccelerationStructureGeometryKHR[1]", [instances_geometry(built.instances.address)])
        tlas_info = v.VkAccelerationStructureBuildGeometryInfoKHR(
            type=v.VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, flags=build_flags(refit, False), mode=mode,
            srcAccelerationStructure=built.tlas if update else None, dstAccelerationStructure=built.tlas,
            geometryCount=1, pGeometries=geometry,
            scratchData=v.VkDeviceOrHostAddressKHR(deviceAddress=scratch_address))
        self._build(fn, cb, [tlas_info], [len(geo.instances)], [geometry])

    @staticmethod
    def _build(fn: Any, cb: Any, infos: list[Any], counts: list[int], keep: list[Any]) -> None:
        v = vk()
        range_structs = [v.ffi.new("VkAccelerationStructureBuildRangeInfoKHR*", {"primitiveCount": n}) for n in counts]
        pointers = v.ffi.new("VkAccelerationStructureBuildRangeInfoKHR*[]", range_structs)
        info_array = v.ffi.new("VkAccelerationStructureBuildGeometryInfoKHR[]", len(infos))
        for i, info in enumerate(infos):
            info_array[i] = info
        fn(cb, len(infos), info_array, pointers)
        keep.extend([range_structs, pointers, info_array, infos])

    def record_frame_build(self, cb: Any, name: str, set_index: int) -> None:
        """A frame's ``accel_build`` of ``name``: nothing for persistent accels without refits."""
        layout = self.layouts[name]
        res = self.resources.get(name, set_index).plan
        if res["lifetime"] in SHARED and not layout["refit"]:
            return
        scratch = self.resources.get(name + ".scratch", set_index)
        align = int(layout["scratch_alignment"])
        address = -(-buffer_address(self.device, scratch.handle) // align) * align
        if name in self.deforming:  # the frame's normals, with their barriers (rgraph.vk.rt_normals)
            self.deformed.record_normals(cb, set_index)
        self.record_build(cb, name, set_index, address, update=res["lifetime"] in SHARED)

    def destroy(self) -> None:
        fn = proc(self.device, "vkDestroyAccelerationStructureKHR")
        seen: set[int] = set()
        for built in self.built.values():
            if id(built) in seen:
                continue
            seen.add(id(built))
            for handle in [*built.blas, built.tlas]:
                fn(self.device.handle, handle, None)
        self.built.clear()
        if self.deformed is not None:
            self.deformed.destroy()
            self.deformed = None
        for buf in reversed(self.buffers):
            buf.destroy()
        self.buffers.clear()
