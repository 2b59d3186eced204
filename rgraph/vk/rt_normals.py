"""The deformable meshes' normals of the ray tracing tables on the GPU (``rgraph.vk.rt_deform``).

The raster path's pass ``shaders/scene/deform_normals.comp`` with ``NORMALS_ONLY``: per
deformable vertex its smoothed normal over the same ``SmoothingTopology`` (the rule of
``rgraph.scene.smoothing``), from set s's host-written positions table (one ring slot, header
alpha 1), into set s's device-local normals table (static meshes' normals uploaded once).
Indices, groups and the CSR lists are in the tables' global vertex numbering (every mesh, mesh
after mesh), so one vertex id addresses the positions, the fallback normals and the output.

``record(cb, s)`` goes into every frame build of an accel built from the deformed geometry
(``AccelSet.record_frame_build``), before the build: a barrier (every earlier access -> the
compute writes: the previous frame's readers of the set, and another build pass's dispatch
of the same frame), one dispatch per deformable mesh, a barrier (compute writes -> shader
reads of every later command). Every pass that reads the normals (the hit / shade passes)
reads that accel, so the plan orders it after the build pass: on one queue the barrier covers
it; across queues the plan's semaphore, whose signal follows the build, continues the chain.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rgraph.vk.device import Device
from rgraph.vk.device_local import barrier
from rgraph.vk.loader import vk
from rgraph.vk.shaders import compile_shader, find_shader
from rgraph.vk.static_buffer import upload_static

SHADER = "scene/deform_normals.comp"
GROUP_SIZE = 64
PUSH_BYTES = 16
BINDINGS = (0, 1, 2, 3, 4, 5, 7, 8)  # header, positions, groups, offsets, triangles, indices, fallback, normals


def global_topology(meshes: list[Any], first_vertex: np.ndarray, deformable: list[int]) -> list[np.ndarray]:
    """(groups (n,), CSR offsets (n + 1,), triangles, indices (3 per triangle)) as uint32 over
    the tables' n vertices; only the deformable meshes' vertices have groups and lists."""
    n = int(first_vertex[-1])
    groups = np.zeros(n, dtype=np.int64)
    counts = np.zeros(n, dtype=np.int64)
    triangles, indices = [], []
    tri_base = 0
    for k in deformable:
        mesh, base = meshes[k], int(first_vertex[k])
        top = mesh.deformer.topology
        count = mesh.data.vertex_count
        groups[base:base + count] = top.group.astype(np.int64) + base
        counts[base:base + count] = np.diff(top.offsets.astype(np.int64))
        triangles.append(top.triangles.astype(np.int64) + tri_base)
        indices.append(mesh.data.indices.astype(np.int64).reshape(-1) + base)
        tri_base += mesh.data.triangle_count
    offsets = np.concatenate([[0], np.cumsum(counts)])
    return [a.astype(np.uint32) for a in (groups, offsets, np.concatenate(triangles), np.concatenate(indices))]


class NormalsGPU:
    """See the module docstring. ``positions``: per set (VkBuffer, bytes) of the host-written
    positions table; ``rest_normals``: the static normals table (float32 bytes)."""

    def __init__(self, device: Device, tables: Any, positions: tuple[tuple[Any, int], ...],
                 rest_normals: bytes) -> None:
        v = vk()
        self.device = device
        self.sets = len(positions)
        meshes = tables.data.meshes
        self.parts = [(int(tables.first_vertex[k]), meshes[k].data.vertex_count, meshes[k].deformer.topology.scale)
                      for k in tables.deformable]
        self.total = int(tables.first_vertex[-1])
        self._objects: list[tuple[str, Any]] = []
        self._buffers: list[tuple[Any, Any]] = []  # (VkBuffer, VkDeviceMemory)
        try:
            storage = v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
            header = np.array([1.0, 0.0, 0.0, 0.0], dtype=np.float32).tobytes()  # alpha 1, slots 0 and 0
            shared = [header, *(a.tobytes() for a in global_topology(meshes, tables.first_vertex, tables.deformable)),
                      rest_normals]
            self.shared = [self._upload(b, storage) for b in shared]
            readable = storage | v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT  # (tests read them back)
            self.normals = [self._upload(rest_normals, readable) for _ in range(self.sets)]
            self._make_pipeline(positions)
        except BaseException:
            self.destroy()
            raise

    def _upload(self, payload: bytes, usage: int) -> tuple[Any, int]:
        handle, memory, size = upload_static(self.device, payload, usage)
        self._buffers.append((handle, memory))
        return handle, size

    def _own(self, destroy: str, handle: Any) -> Any:
        self._objects.append((destroy, handle))
        return handle

    def _make_pipeline(self, positions: tuple[tuple[Any, int], ...]) -> None:
        v = vk()
        dev = self.device.handle
        ssbo = v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        layout_bindings = [v.VkDescriptorSetLayoutBinding(binding=b, descriptorType=ssbo, descriptorCount=1,
                                                          stageFlags=v.VK_SHADER_STAGE_COMPUTE_BIT) for b in BINDINGS]
        self.set_layout = self._own("vkDestroyDescriptorSetLayout", v.vkCreateDescriptorSetLayout(
            dev, v.VkDescriptorSetLayoutCreateInfo(bindingCount=len(BINDINGS), pBindings=layout_bindings), None))
        pool = self._own("vkDestroyDescriptorPool", v.vkCreateDescriptorPool(dev, v.VkDescriptorPoolCreateInfo(
            maxSets=self.sets, poolSizeCount=1,
            pPoolSizes=[v.VkDescriptorPoolSize(type=ssbo, descriptorCount=len(BINDINGS) * self.sets)]), None))
        self.descriptor_sets = list(v.vkAllocateDescriptorSets(dev, v.VkDescriptorSetAllocateInfo(
            descriptorPool=pool, descriptorSetCount=self.sets, pSetLayouts=[self.set_layout] * self.sets)))
        header, groups, offsets, triangles, indices, fallback = self.shared
        for s in range(self.sets):
            buffers = [header, positions[s], groups, offsets, triangles, indices, fallback, self.normals[s]]
            infos = [v.VkDescriptorBufferInfo(buffer=h, offset=0, range=size) for h, size in buffers]
            writes = [v.VkWriteDescriptorSet(dstSet=self.descriptor_sets[s], dstBinding=b, descriptorCount=1,
                                             descriptorType=ssbo, pBufferInfo=[info])
                      for b, info in zip(BINDINGS, infos, strict=True)]
            v.vkUpdateDescriptorSets(dev, len(writes), writes, 0, None)
        push = v.VkPushConstantRange(stageFlags=v.VK_SHADER_STAGE_COMPUTE_BIT, offset=0, size=PUSH_BYTES)
        self.pipeline_layout = self._own("vkDestroyPipelineLayout", v.vkCreatePipelineLayout(
            dev, v.VkPipelineLayoutCreateInfo(setLayoutCount=1, pSetLayouts=[self.set_layout],
                                              pushConstantRangeCount=1, pPushConstantRanges=[push]), None))
        spirv = compile_shader(find_shader(SHADER), defines={"NORMALS_ONLY": 1}).spirv
        module = self._own("vkDestroyShaderModule", v.vkCreateShaderModule(dev, v.VkShaderModuleCreateInfo(
            codeSize=len(spirv), pCode=spirv), None))
        stage = v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_COMPUTE_BIT, module=module, pName="main")
        self.pipeline = self._own("vkDestroyPipeline", v.vkCreateComputePipelines(dev, None, 1, [
            v.VkComputePipelineCreateInfo(stage=stage, layout=self.pipeline_layout)], None)[0])
        self._push = [v.ffi.new("char[]", np.array([first, count, self.total], dtype=np.uint32).tobytes()
                                + np.float32(scale).tobytes()) for first, count, scale in self.parts]

    def record(self, cb: Any, frame_set: int) -> None:
        v = vk()
        out = [self.normals[frame_set][0]]
        every = v.VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT
        compute = v.VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT
        write, read = v.VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, v.VK_ACCESS_2_SHADER_STORAGE_READ_BIT
        barrier(cb, out, every, write, compute, write)  # earlier reads (WAR) and writes (WAW) first
        v.vkCmdBindPipeline(cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, self.pipeline)
        v.vkCmdBindDescriptorSets(cb, v.VK_PIPELINE_BIND_POINT_COMPUTE, self.pipeline_layout, 0, 1,
                                  [self.descriptor_sets[frame_set]], 0, None)
        for (_first, count, _scale), push in zip(self.parts, self._push, strict=True):
            v.vkCmdPushConstants(cb, self.pipeline_layout, v.VK_SHADER_STAGE_COMPUTE_BIT, 0, PUSH_BYTES, push)
            v.vkCmdDispatch(cb, (count + GROUP_SIZE - 1) // GROUP_SIZE, 1, 1)
        barrier(cb, out, compute, write, every, read)

    def normal_buffers(self) -> tuple[tuple[Any, int], ...]:
        return tuple(self.normals)

    def destroy(self) -> None:
        v = vk()
        dev = self.device.handle
        for destroy, handle in reversed(self._objects):
            getattr(v, destroy)(dev, handle, None)
        self._objects = []
        for handle, memory in reversed(self._buffers):
            v.vkDestroyBuffer(dev, handle, None)
            v.vkFreeMemory(dev, memory, None)
        self._buffers = []
