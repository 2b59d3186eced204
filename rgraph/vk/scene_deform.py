"""The deformable meshes on the GPU: the CPU writes positions, a compute pass the vertices.

Host-visible, written by the CPU: a *ring* of ``SLOTS`` position states (every deformable
vertex, float32), and per frame-in-flight set a 16-byte *header* (``alpha``, the previous and
the current state's slot). Without a logic thread, the render thread writes the next frame's
positions right after a frame's submits (``prepare``: into one of ``AHEAD_SLOTS``, which no
frame in flight reads) and the frame's update points its set's header at that slot (alpha 1);
a frame not prepared writes slot s of its set s then. With one (``rgraph.vk.runtime.logic``) the logic thread writes
each tick's positions into a free slot (``write_slot``: not the published pair, not a pair a
frame in flight reads; all under ``lock``) and the render thread writes only the header
(``rgraph.vk.scene_frame``: it marks the slots it takes in ``in_use`` under the same lock).
Device-local, per set: the vertex buffer (position, normal: ``packing.VERTEX_BYTES``) the
scene's draws bind and a tangent buffer (vec4: xyz, w the bitangent's sign), both written by
``shaders/scene/deform_normals.comp``. Shared and uploaded once: the smoothing topology
(``rgraph.scene.smoothing``: groups, the CSR group -> triangles, indices), UVs and the rest
normals (the fallback).

``record(cb, s)`` goes at the start of the frame's first batch that uses the scene on the
graphics queue (``rgraph.vk.runtime.commands``): a barrier (earlier draws' vertex reads before
the writes: write-after-read), one dispatch per deformable mesh, a barrier (compute writes
before vertex input and shader reads of the rest of the frame).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from rgraph.scene import packing
from rgraph.scene.shapes import MeshData
from rgraph.scene.smoothing import SmoothingTopology
from rgraph.vk.device import Device
from rgraph.vk.device_local import barrier
from rgraph.vk.loader import vk
from rgraph.vk.shaders import compile_shader, find_shader

SHADER = "scene/deform_normals.comp"
GROUP_SIZE = 64
HEADER_BYTES = 16
SLOTS = 8  # >= 2 sets x 2 slots in flight + the published pair + the one being written
AHEAD_SLOTS = (2, 3, 4)  # no logic thread: frames written ahead of their fence wait (DeformGPU.prepare)
TANGENT_BYTES = 16
PUSH_BYTES = 16


@dataclass(frozen=True)
class DeformPart:
    """One deformable mesh: its rest mesh, smoothing topology, first vertex in the state, and
    the ``rgraph.scene.deform.Deformer`` that writes its positions (None: written by the caller)."""

    data: MeshData
    topology: SmoothingTopology
    base: int
    deformer: Any = None


class DeformGPU:
    """See the module docstring. ``parts``: one ``DeformPart`` per deformable mesh;
    ``device_buffer(size, usage)``, ``host_buffer(size, usage)`` and ``upload([(buffer, bytes)])``
    come from ``SceneGPU`` (it owns and destroys the buffers)."""

    def __init__(self, device: Device, sets: int, parts: list[DeformPart], *, device_buffer: Any,
                 host_buffer: Any, upload: Any) -> None:
        v = vk()
        self.device = device
        self.sets = sets
        self.parts = parts
        self.total = sum(part.data.vertex_count for part in parts)
        self.recorded = [False] * sets
        self._objects: list[tuple[str, Any]] = []
        groups, offsets, triangles, indices, uvs, fallback = [], [], [], [], [], []
        tri_base = 0
        for part in parts:
            top, base, data = part.topology, part.base, part.data
            groups.append(top.group.astype(np.int64) + base)
            starts = top.offsets[:-1].astype(np.int64) + sum(len(t) for t in triangles)
            offsets.append(starts)
            triangles.append(top.triangles.astype(np.int64) + tri_base)
            indices.append(data.indices.astype(np.int64).reshape(-1) + base)
            uvs.append(data.uvs if data.uvs is not None else np.zeros((data.vertex_count, 2)))
            fallback.append(data.normals)
            tri_base += data.triangle_count
        k = sum(len(t) for t in triangles)
        tables = [np.concatenate(groups), np.concatenate([*offsets, [k]]), np.concatenate(triangles),
                  np.concatenate(indices)]
        storage = v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
        shared = [arr.astype(np.uint32).tobytes() for arr in tables]
        shared += [np.concatenate(uvs).astype(np.float32).tobytes(), np.concatenate(fallback).astype(np.float32).tobytes()]
        self.shared = [device_buffer(len(b), storage) for b in shared]
        upload(list(zip(self.shared, shared, strict=True)))
        self.ring_bytes = SLOTS * 3 * 4 * self.total
        self.ring = host_buffer(self.ring_bytes, storage)
        self.headers = [host_buffer(HEADER_BYTES, storage) for _ in range(sets)]
        self.vertex_buffers = [device_buffer(self.total * packing.VERTEX_BYTES,
                                             storage | v.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT) for _ in range(sets)]
        self.tangent_buffers = [device_buffer(self.total * TANGENT_BYTES, storage) for _ in range(sets)]
        # numpy views of the mapped memory: the ring (SLOTS, total, 3); per set (alpha, slots)
        self.slots = np.frombuffer(self.ring.mapped, dtype=np.float32, count=self.ring_bytes // 4).reshape(
            SLOTS, self.total, 3)
        self.header_views = []  # NumPy views (reading); header_words: cffi pointers (the per-frame writes)
        self.header_words = []
        for buf in self.headers:
            f = np.frombuffer(buf.mapped, dtype=np.float32, count=4)
            self.header_views.append((f, f.view(np.uint32)))
            raw = v.ffi.from_buffer(buf.mapped)
            self.header_words.append((v.ffi.cast("float *", raw), v.ffi.cast("uint32_t *", raw)))
        self.lock = threading.Lock()  # the logic thread's too (LogicThread(lock=...)): slots change hands under it
        self.in_use: list[tuple[int, int]] = [(s, s) for s in range(sets)]  # per set: the slots its frame reads
        for s in range(sets):
            self.set_header(s, 1.0, s, s)
        self._ahead: tuple[int, float, int] | None = None  # (content frame, seconds, slot) of prepare
        self._make_pipeline()

    # ----------------------------------------------------------------- per frame (host)
    def write(self, seconds: float, frame_set: int, frame: int | None = None) -> None:
        """Without a logic thread: set ``frame_set`` shows the positions at ``seconds`` (header:
        alpha 1, one slot): the slot ``prepare`` filled for content frame ``frame`` ahead of
        time, else slot ``frame_set``, written now."""
        ahead = self._ahead
        if frame is not None and ahead is not None and ahead[0] == frame and ahead[1] == seconds:
            self.set_header(frame_set, 1.0, ahead[2], ahead[2])
            return
        self.write_positions(frame_set, seconds)
        self.set_header(frame_set, 1.0, frame_set, frame_set)

    def prepare(self, frame: int, seconds: float) -> None:
        """Without a logic thread, right after the previous frame's submits (the CPU is still
        warm; positions written after the fence wait took 5-8x as long on the H200 host):
        content frame ``frame``'s positions into ``AHEAD_SLOTS[frame % 3]``, a slot neither
        frame in flight reads (they read the two other ahead slots, or slots 0 and 1)."""
        slot = AHEAD_SLOTS[frame % len(AHEAD_SLOTS)]
        self._ahead = None  # the slot is being written
        self.write_positions(slot, seconds)
        self._ahead = (frame, seconds, slot)

    def write_positions(self, slot: int, seconds: float) -> None:
        cur = self.slots[slot]
        for part in self.parts:
            part.deformer.write_positions(seconds, cur[part.base:part.base + part.data.vertex_count])

    def write_slot(self, seconds: float, published: Any) -> int:
        """The logic thread's tick: the positions at ``seconds`` into a slot that no frame set
        reads (``in_use``) and ``published()`` (the slots of the states a frame may still take)
        does not name; its index. Slots in use and published: at most 6 of ``SLOTS``."""
        with self.lock:
            busy = {*published(), *(x for pair in self.in_use for x in pair)}
            slot = next(k for k in range(SLOTS) if k not in busy)
        self.write_positions(slot, seconds)
        return slot

    def set_header(self, frame_set: int, alpha: float, prev: int, cur: int) -> None:
        """Set ``frame_set``'s frame mixes slots ``prev`` and ``cur`` with weight ``alpha`` (1: cur)."""
        f, u = self.header_words[frame_set]
        f[0] = alpha
        u[1] = prev
        u[2] = cur

    # ----------------------------------------------------------------- recording
    def record(self, cb: Any, frame_set: int) -> None:
        v = vk()
        stage2 = v.VK_PIPELINE_STAGE_2_VERTEX_ATTRIBUTE_INPUT_BIT | v.VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT
        readers = stage2 | v.VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | v.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT
        outputs = [self.vertex_buffers[frame_set].handle, self.tangent_buffers[frame_set].handle]
        barrier(cb, outputs, readers, 0, v.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                      v.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT)
        v.vkCmdBindPipeline(cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, self.pipeline)
        v.vkCmdBindDescriptorSets(cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, self.pipeline_layout, 0, 1,
                                  [self.descriptor_sets[frame_set]], 0, None)
        for part in self.parts:
            count = part.data.vertex_count
            push = (np.array([part.base, count, self.total], dtype=np.uint32).tobytes()
                    + np.float32(part.topology.scale).tobytes())
            data = v.ffi.new("char[]", push)
            v.vkCmdPushConstants(cb, self.pipeline_layout, v.VK_SHADER_STAGE_COMPUTE_BIT, 0, PUSH_BYTES, data)
            v.vkCmdDispatch(cb, (count + GROUP_SIZE - 1) // GROUP_SIZE, 1, 1)
        barrier(cb, outputs, v.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, v.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      readers, v.VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT | v.VK_ACCESS_2_SHADER_STORAGE_READ_BIT)
        self.recorded[frame_set] = True

    # ----------------------------------------------------------------- creation, teardown
    def _own(self, destroy: str, handle: Any) -> Any:
        self._objects.append((destroy, handle))
        return handle

    def _make_pipeline(self) -> None:
        v = vk()
        dev = self.device.handle
        ssbo = v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        count = 10
        bindings = [v.VkDescriptorSetLayoutBinding(binding=b, descriptorType=ssbo, descriptorCount=1,
                                                   stageFlags=v.VK_SHADER_STAGE_COMPUTE_BIT) for b in range(count)]
        self.set_layout = self._own("vkDestroyDescriptorSetLayout", v.vkCreateDescriptorSetLayout(
            dev, v.VkDescriptorSetLayoutCreateInfo(bindingCount=count, pBindings=bindings), None))
        pool = self._own("vkDestroyDescriptorPool", v.vkCreateDescriptorPool(dev, v.VkDescriptorPoolCreateInfo(
            maxSets=self.sets, poolSizeCount=1,
            pPoolSizes=[v.VkDescriptorPoolSize(type=ssbo, descriptorCount=count * self.sets)]), None))
        self.descriptor_sets = list(v.vkAllocateDescriptorSets(dev, v.VkDescriptorSetAllocateInfo(
            descriptorPool=pool, descriptorSetCount=self.sets, pSetLayouts=[self.set_layout] * self.sets)))
        for s in range(self.sets):
            buffers = [(self.headers[s].handle, HEADER_BYTES), (self.ring.handle, self.ring_bytes),
                       *((b.handle, b.size) for b in self.shared),
                       (self.vertex_buffers[s].handle, self.vertex_buffers[s].size),
                       (self.tangent_buffers[s].handle, self.tangent_buffers[s].size)]
            infos = [v.VkDescriptorBufferInfo(buffer=h, offset=0, range=size) for h, size in buffers]
            writes = [v.VkWriteDescriptorSet(dstSet=self.descriptor_sets[s], dstBinding=b, descriptorCount=1,
                                             descriptorType=ssbo, pBufferInfo=[info]) for b, info in enumerate(infos)]
            v.vkUpdateDescriptorSets(dev, len(writes), writes, 0, None)
        push = v.VkPushConstantRange(stageFlags=v.VK_SHADER_STAGE_COMPUTE_BIT, offset=0, size=PUSH_BYTES)
        self.pipeline_layout = self._own("vkDestroyPipelineLayout", v.vkCreatePipelineLayout(
            dev, v.VkPipelineLayoutCreateInfo(setLayoutCount=1, pSetLayouts=[self.set_layout],
                                              pushConstantRangeCount=1, pPushConstantRanges=[push]), None))
        spirv = compile_shader(find_shader(SHADER)).spirv
        module = self._own("vkDestroyShaderModule", v.vkCreateShaderModule(dev, v.VkShaderModuleCreateInfo(
            codeSize=len(spirv), pCode=spirv), None))
        stage = v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_COMPUTE_BIT, module=module, pName="main")
        self.pipeline = self._own("vkDestroyPipeline", v.vkCreateComputePipelines(dev, None, 1, [
            v.VkComputePipelineCreateInfo(stage=stage, layout=self.pipeline_layout)], None)[0])

    def destroy(self) -> None:
        """The pipeline and descriptor objects (the buffers are ``SceneGPU``'s)."""
        v = vk()
        for destroy, handle in reversed(self._objects):
            getattr(v, destroy)(self.device.handle, handle, None)
        self._objects = []
