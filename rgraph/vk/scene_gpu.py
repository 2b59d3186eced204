"""The scene on the GPU: descriptor set 0 of scene passes (``shaders/scene/scene.glsl``) and geometry.

Built once per run from ``plan["scene_source"]`` by the executor (``Executor._scene``):

- rigid geometry (every mesh's vertices; all indices), the materials and the authored lights
  live in device-local buffers, filled once through a host staging buffer and
  ``vkCmdCopyBuffer`` followed by a buffer barrier COPY/TRANSFER_WRITE -> ALL_COMMANDS/MEMORY_READ
  in the same command buffer (a fence wait alone does not make device writes visible);
- per frame-in-flight set, host-visible and written in ``update(frame, frame_set)``: the Frame
  uniform, the Draws and Decals storage buffers (camera-relative, float64 on the CPU), and the
  deformable meshes' positions (deformed on the CPU every frame); their normals and tangents
  are computed on the GPU (``rgraph.vk.scene_deform``: ``record_deform`` at the start of the
  frame's first scene batch on the graphics queue), into the vertex buffers the draws bind.
- skinning (bindings 5-7, ``rgraph.vk.skin_gpu.SkinGPU``): joints and weights, the ring of
  packed logic states and each set's interpolation factor.

Passes use ``set_layout`` (set 0 of their pipeline layouts), ``descriptor_set(frame_set)``,
``vertex_input`` and ``draw(rec, frame_set)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rgraph.scene import packing
from rgraph.scene.build import SceneData, load_scene_data
from rgraph.vk.device import Device
from rgraph.vk.device_local import DeviceBuffer, DeviceLocal
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.passkit import VertexInput
from rgraph.vk.resources import HostBuffer
from rgraph.vk.runtime.logic import interpolation_alpha

BINDING_FRAME, BINDING_DRAWS, BINDING_MATERIALS, BINDING_SCENE_LIGHTS, BINDING_DECALS = range(5)
BINDING_SKIN_VERTICES, BINDING_BONES, BINDING_SKIN_FRAME = range(5, 8)  # rgraph.vk.skin_gpu


@dataclass(frozen=True)
class DrawCall:
    deformable: bool
    index_count: int
    first_index: int
    vertex_offset: int
    instances: int
    first_instance: int


class SceneGPU:
    """See the module docstring. ``submit_once(queue, record_fn)`` records ``record_fn(cb)``,
    submits it on the plan queue and waits for it."""

    def __init__(self, device: Device, plan: dict, sets: int, submit_once: Any) -> None:
        source = plan.get("scene_source")
        if not source:
            raise ExecutionError("the plan names no scene file (scene_source); scene passes need one")
        self.device = device
        self.sets = sets
        self.extent: tuple[int, int] = tuple(plan.get("size") or (64, 64))  # type: ignore[assignment]
        self.plan_logic_hz = plan.get("logic_hz")  # skinning's logic rate (default 60 Hz)
        try:
            self.data: SceneData = load_scene_data(source, self.extent, int(plan.get("camera", 0)))
        except (OSError, ValueError) as exc:
            raise ExecutionError(f"scene {source}: {exc}") from None
        self._device_local = DeviceLocal(device)
        self._host: list[HostBuffer] = []
        self._pool = None
        self.skin = None
        self.set_layout = None
        self._sets: list[Any] = []
        self._camera_written: list[bytes | None] = [None] * sets  # per set: the camera its Draws/Decals are for
        self.logic: Any = None  # rgraph.vk.runtime.logic.LogicThread (attach_logic)
        self.ticks_taken: list[tuple[int, int] | None] = [None] * sets  # per set: the logic ticks its frame mixes
        self.alpha_range = [1.0, 0.0]
        self.deform: Any = None  # rgraph.vk.scene_deform.DeformGPU when the scene has deformable meshes
        try:
            self._build(submit_once)
        except BaseException:
            self.destroy()
            raise

    # ----------------------------------------------------------------- python-side accessors
    @property
    def lights(self) -> int:
        return len(self.data.lights)

    @property
    def shadow_lights(self) -> int:
        return len(self.data.shadow_lights)

    @property
    def point_lights(self) -> int:
        return self.data.point_light_count

    @property
    def decals(self) -> int:
        return len(self.data.decals)

    @property
    def draw_count(self) -> int:
        return self.data.draw_count

    def camera(self, frame: int = 0):
        """The float64 ``rgraph.scene.camera.CameraState`` of ``frame``."""
        return self.data.camera(frame)

    @property
    def vertex_input(self) -> VertexInput:
        return VertexInput(stride=packing.VERTEX_BYTES,
                           attributes=[(0, "r32g32b32_sfloat", 0), (1, "r32g32b32_sfloat", 12)])

    @property
    def position_input(self) -> VertexInput:
        """Positions only (depth-only shaders, ``SCENE_POSITION_ONLY``): same buffers and stride."""
        return VertexInput(stride=packing.VERTEX_BYTES, attributes=[(0, "r32g32b32_sfloat", 0)])

    def descriptor_set(self, frame_set: int) -> Any:
        return self._sets[frame_set]

    # ----------------------------------------------------------------- creation
    def _device_buffer(self, size: int, usage: int) -> DeviceBuffer:
        return self._device_local.buffer(size, usage)

    def _host_buffer(self, size: int, usage: int) -> HostBuffer:
        buf = HostBuffer.create(self.device, size, usage)
        self._host.append(buf)
        return buf

    def _build(self, submit_once: Any) -> None:
        import numpy as np

        v = vk()
        data = self.data
        # geometry: rigid vertices in one device-local buffer, deformable ones per set in host memory
        rigid_vertices, indices, calls = [], [], []
        rigid_base = deform_base = first_index = 0
        self._deform_layout: list[tuple[Any, int]] = []  # (mesh, vertex offset) in the per-set buffers
        skinned: list[tuple[Any, int]] = []  # (mesh, first vertex in the rigid vertex buffer)
        for mesh in data.meshes:
            count = mesh.data.triangle_count * 3
            indices.append(mesh.data.indices.reshape(-1))
            if mesh.deformer is None:
                if mesh.animator is not None:
                    skinned.append((mesh, rigid_base))
                rigid_vertices.append(packing.vertex_bytes(mesh.data))
                calls.append(DrawCall(False, count, first_index, rigid_base, mesh.instances, mesh.first_draw))
                rigid_base += mesh.data.vertex_count
            else:
                self._deform_layout.append((mesh, deform_base))
                calls.append(DrawCall(True, count, first_index, deform_base, mesh.instances, mesh.first_draw))
                deform_base += mesh.data.vertex_count
            first_index += count
        self.calls = calls
        index_bytes = np.concatenate(indices).astype(np.uint32).tobytes() if indices else b""
        vertex_bytes = b"".join(rigid_vertices)
        materials = packing.materials_bytes(data)
        scene_lights = packing.scene_lights_bytes(data)
        uploads = []
        storage = v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
        self.index_buffer = self._device_buffer(len(index_bytes), v.VK_BUFFER_USAGE_INDEX_BUFFER_BIT)
        uploads.append((self.index_buffer, index_bytes))
        self.vertex_buffer = self._device_buffer(len(vertex_bytes), v.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT)
        uploads.append((self.vertex_buffer, vertex_bytes))
        self.materials_buffer = self._device_buffer(len(materials), storage)
        uploads.append((self.materials_buffer, materials))
        self.scene_lights_buffer = self._device_buffer(len(scene_lights), storage)
        uploads.append((self.scene_lights_buffer, scene_lights))
        self._upload(submit_once, [(b, d) for b, d in uploads if d])
        from rgraph.vk.skin_gpu import SkinGPU

        self.skin = SkinGPU(self.device, data, self.sets, skinned, rigid_base,
                            float(self.plan_logic_hz) if self.plan_logic_hz else 60.0)

        self.frame_buffers = [self._host_buffer(packing.FRAME_BYTES, v.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT)
                              for _ in range(self.sets)]
        draws_size = len(packing.draws_bytes(data, 0))
        self.draw_buffers = [self._host_buffer(draws_size, storage) for _ in range(self.sets)]
        decals_size = max(len(data.decals), 1) * packing.DECAL_BYTES
        self.decal_buffers = [self._host_buffer(decals_size, storage) for _ in range(self.sets)]
        if deform_base:
            from rgraph.vk.scene_deform import DeformGPU, DeformPart

            parts = [DeformPart(mesh.data, mesh.deformer.topology, base, mesh.deformer)
                     for mesh, base in self._deform_layout]
            self.deform = DeformGPU(self.device, self.sets, parts, device_buffer=self._device_buffer,
                                    host_buffer=self._host_buffer, upload=lambda ups: self._upload(submit_once, ups))
        self._make_descriptors(materials_size=len(materials), lights_size=len(scene_lights), draws_size=draws_size,
                               decals_size=decals_size)
        for s in range(self.sets):
            self.update(0, s)

    def _upload(self, submit_once: Any, uploads: list[tuple[DeviceBuffer, bytes]]) -> None:
        self._device_local.upload(submit_once, uploads)

    def _make_descriptors(self, *, materials_size: int, lights_size: int, draws_size: int, decals_size: int) -> None:
        v = vk()
        dev = self.device.handle
        ubo, ssbo = v.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        kinds = [(BINDING_FRAME, ubo), (BINDING_DRAWS, ssbo), (BINDING_MATERIALS, ssbo),
                 (BINDING_SCENE_LIGHTS, ssbo), (BINDING_DECALS, ssbo), (BINDING_SKIN_VERTICES, ssbo),
                 (BINDING_BONES, ssbo), (BINDING_SKIN_FRAME, ubo)]
        bindings = [v.VkDescriptorSetLayoutBinding(binding=b, descriptorType=t, descriptorCount=1,
                                                   stageFlags=v.VK_SHADER_STAGE_ALL) for b, t in kinds]
        self.set_layout = v.vkCreateDescriptorSetLayout(dev, v.VkDescriptorSetLayoutCreateInfo(
            bindingCount=len(bindings), pBindings=bindings), None)
        sizes = [v.VkDescriptorPoolSize(type=ubo, descriptorCount=2 * self.sets),
                 v.VkDescriptorPoolSize(type=ssbo, descriptorCount=6 * self.sets)]
        self._pool = v.vkCreateDescriptorPool(dev, v.VkDescriptorPoolCreateInfo(
            maxSets=self.sets, poolSizeCount=len(sizes), pPoolSizes=sizes), None)
        self._sets = list(v.vkAllocateDescriptorSets(dev, v.VkDescriptorSetAllocateInfo(
            descriptorPool=self._pool, descriptorSetCount=self.sets, pSetLayouts=[self.set_layout] * self.sets)))
        for s in range(self.sets):
            sources = [(BINDING_FRAME, ubo, self.frame_buffers[s].handle, packing.FRAME_BYTES),
                       (BINDING_DRAWS, ssbo, self.draw_buffers[s].handle, draws_size),
                       (BINDING_MATERIALS, ssbo, self.materials_buffer.handle, materials_size),
                       (BINDING_SCENE_LIGHTS, ssbo, self.scene_lights_buffer.handle, lights_size),
                       (BINDING_DECALS, ssbo, self.decal_buffers[s].handle, decals_size)]
            skin = [*self.skin.descriptors(), self.skin.frame_descriptor(s)]
            sources += [(b, ubo if kind == "uniform" else ssbo, buf.handle, size) for b, kind, buf, size in skin]
            infos = [v.VkDescriptorBufferInfo(buffer=h, offset=0, range=size) for _b, _t, h, size in sources]
            writes = [v.VkWriteDescriptorSet(dstSet=self._sets[s], dstBinding=b, descriptorCount=1, descriptorType=t,
                                             pBufferInfo=[info])
                      for (b, t, _h, _size), info in zip(sources, infos, strict=True)]
            v.vkUpdateDescriptorSets(dev, len(writes), writes, 0, None)

    # ----------------------------------------------------------------- per frame
    def update(self, frame: int, frame_set: int) -> None:
        """Write set ``frame_set``'s host memory for ``frame`` (its previous use has finished)."""
        data = self.data
        logic = self.logic
        if logic is None:
            seconds = data.seconds(frame)
        else:  # between the logic thread's last two states
            prev, cur = logic.latest() if self.deform is None else self.deform.take(frame_set, logic.latest)
            alpha = interpolation_alpha(logic.clock(), cur.wall, logic.hz)
            seconds = prev.seconds + alpha * (cur.seconds - prev.seconds)
            self.alpha_range[0] = min(self.alpha_range[0], alpha)
            self.alpha_range[1] = max(self.alpha_range[1], alpha)
        self.frame_buffers[frame_set].write(packing.frame_bytes(data, frame, seconds))
        camera = data.camera(frame).position.tobytes()
        if self._camera_written[frame_set] != camera:  # camera-relative tables change with the camera only
            self.draw_buffers[frame_set].write(packing.draws_bytes(data, frame))
            if data.decals:
                self.decal_buffers[frame_set].write(packing.decals_bytes(data, frame))
            self._camera_written[frame_set] = camera
        if logic is None:
            if self.skin is not None:
                self.skin.update(seconds, frame_set)
            if self.deform is not None:
                self.deform.write(seconds, frame_set)
            return
        if self.skin is not None:  # the logic thread packed these states (logic_step)
            self.skin.show(frame_set, prev.tick, cur.tick, alpha)
        if self.deform is not None:
            self.deform.set_header(frame_set, alpha, prev.value, cur.value)  # the logic wrote the slots
        self.ticks_taken[frame_set] = (prev.tick, cur.tick)

    def attach_logic(self, logic: Any) -> None:
        """Take scene time and deformable positions from ``logic`` (a started-on-demand
        ``rgraph.vk.runtime.logic.LogicThread`` whose step is ``logic_step`` and whose lock is
        ``deform.lock``)."""
        self.logic = logic
        if self.skin is not None:
            self.skin.logic_hz = float(logic.hz)  # skinning's logic ticks are this thread's
        self.ticks_taken = [None] * self.sets
        self.alpha_range = [1.0, 0.0]  # (min, max) of the alphas used, for the run's report

    def logic_step(self, seconds: float) -> Any:
        """One logic tick at scene time ``seconds`` (the logic thread): the deformable positions
        written into a free ring slot; the slot (None: no deformable meshes)."""
        if self.skin is not None and self.skin.active:  # packed here, copied by the render thread
            self.skin.state(round(seconds * self.logic.hz))
        if self.deform is None:
            return None
        return self.deform.write_slot(seconds, self.logic.published)

    def record_deform(self, cb: Any, frame_set: int) -> None:
        """The deformable vertices' compute pass and its barriers (nothing without deformable meshes)."""
        if self.deform is not None:
            self.deform.record(cb, frame_set)

    def draw(self, rec: Any, frame_set: int, share: Any = None) -> None:
        """Bind vertex and index buffers and record one drawIndexed per mesh
        (instances = the mesh's instances, firstInstance = its first draw index).
        ``share = [device, devices]`` (sort-last, ``params["rgraph.draws"]``): only this device's
        calls (``rgraph.vk.multi.shares``: balanced by triangle count)."""
        calls = self.calls
        if share is not None:
            from rgraph.vk.multi.shares import share_of

            calls = share_of(calls, int(share[0]), int(share[1]))
        if not calls:
            return
        rec.bind_index_buffer(self.index_buffer.handle)
        bound = None
        if any(call.deformable for call in calls) and not self.deform.recorded[frame_set]:
            raise ExecutionError("deformable meshes drawn before their compute pass was recorded (the draw is not "
                                 "on the graphics queue after the frame's first scene batch)")
        for call in calls:
            want = self.deform.vertex_buffers[frame_set].handle if call.deformable else self.vertex_buffer.handle
            if want is not bound:
                rec.bind_vertex_buffers([want])
                bound = want
            rec.draw_indexed(call.index_count, call.instances, call.first_index, call.vertex_offset,
                             call.first_instance)

    # ----------------------------------------------------------------- teardown
    def destroy(self) -> None:
        v = vk()
        dev = self.device.handle
        if self.deform is not None:
            self.deform.destroy()
            self.deform = None
        if self._pool is not None:
            v.vkDestroyDescriptorPool(dev, self._pool, None)
            self._pool = None
            self._sets = []
        if self.set_layout is not None:
            v.vkDestroyDescriptorSetLayout(dev, self.set_layout, None)
            self.set_layout = None
        for buf in reversed(self._host):
            buf.destroy()
        self._host = []
        self._device_local.destroy()
        if self.skin is not None:
            self.skin.destroy()
            self.skin = None
