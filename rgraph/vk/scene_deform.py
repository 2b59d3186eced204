"""The deformable meshes on the GPU: the CPU writes positions, a compute pass the vertices.

Per frame-in-flight set: a host-visible *state* buffer (``alpha``, then two position states
of every deformable vertex, float32: the previous logic state and the current one), written
by the CPU; a device-local vertex buffer (position, normal: ``packing.VERTEX_BYTES``) that the
scene's draws bind, and a device-local tangent buffer (vec4: xyz, w the bitangent's sign),
both written by ``shaders/scene/deform_normals.comp``. Shared and uploaded once: the smoothing
topology (``rgraph.scene.smoothing``: groups, the CSR group -> triangles, indices), UVs and
the rest normals (the fallback).

``record(cb, s)`` goes at the start of the frame's first batch that uses the scene on the
graphics queue (``rgraph.vk.runtime.commands``): a barrier (earlier draws' vertex reads before
the writes: write-after-read), one dispatch per deformable mesh, a barrier (compute writes
before vertex input and shader reads of the rest of the frame).
"""

from __future__ import annotations

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
        self.state_bytes = HEADER_BYTES + 2 * 3 * 4 * self.total
        self.states = [host_buffer(self.state_bytes, storage) for _ in range(sets)]
        self.vertex_buffers = [device_buffer(self.total * packing.VERTEX_BYTES,
                                             storage | v.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT) for _ in range(sets)]
        self.tangent_buffers = [device_buffer(self.total * TANGENT_BYTES, storage) for _ in range(sets)]
        # numpy views of the mapped state: alpha, prev (total, 3), cur (total, 3)
        self.views = []
        for buf in self.states:
            flat = np.frombuffer(buf.mapped, dtype=np.float32, count=self.state_bytes // 4)
            self.views.append((flat[:1], flat[4:4 + 3 * self.total].reshape(-1, 3),
                               flat[4 + 3 * self.total:].reshape(-1, 3)))
        for alpha, _prev, _cur in self.views:
            alpha[0] = 1.0
        self._make_pipeline()

    # ----------------------------------------------------------------- per frame (host)
    def write(self, seconds: float, frame_set: int) -> None:
        """The deformed positions at ``seconds`` as the current state (alpha stays 1)."""
        _alpha, _prev, cur = self.views[frame_set]
        for part in self.parts:
            part.deformer.write_positions(seconds, cur[part.base:part.base + part.data.vertex_count])

    def positions_at(self, seconds: float) -> np.ndarray:
        """Every deformable vertex's position at ``seconds``, (total, 3) float32, a new array
        (the logic thread's state: ``rgraph.vk.runtime.logic``)."""
        out = np.empty((self.total, 3), dtype=np.float32)
        for part in self.parts:
            part.deformer.write_positions(seconds, out[part.base:part.base + part.data.vertex_count])
        return out

    def write_states(self, frame_set: int, prev: np.ndarray | None, cur: np.ndarray | None, alpha: float) -> None:
        """Logic states (``(total, 3)`` float32 each; None: unchanged since this set's last write)
        and the interpolation weight ``alpha`` in [0, 1] (0: prev, 1: cur)."""
        a, p, c = self.views[frame_set]
        if prev is not None:
            p[...] = prev
        if cur is not None:
            c[...] = cur
        a[0] = alpha

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
        count = 9
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
            buffers = [(self.states[s].handle, self.state_bytes), *((b.handle, b.size) for b in self.shared),
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
