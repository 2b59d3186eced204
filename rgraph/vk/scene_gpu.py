"""The scene on the GPU: descriptor set 0 of scene passes (``shaders/scene/scene.glsl``) and geometry.

Built once per run from ``plan["scene_source"]`` by the executor (``Executor._scene``):

- rigid geometry (every mesh's vertices; all indices, placed by the TLSF allocator in one
  buffer each), the materials, the authored lights, the mesh table (binding 6) and, with
  ``draw.mode=gpu`` (``rgraph.vk.scene_modes``), the persistent per-instance data (binding 1)
  live in device-local buffers, filled once through a host staging buffer and
  ``vkCmdCopyBuffer`` followed by a buffer barrier COPY/TRANSFER_WRITE -> ALL_COMMANDS/MEMORY_READ
  in the same command buffer (a fence wait alone does not make device writes visible);
- per frame-in-flight set, host-visible and written in ``update(frame, frame_set)``: the Frame
  uniform, the Views uniform (binding 5, ``views=2``), the Draws (draw modes cpu and naive) and
  Decals storage buffers (camera-relative, float64 on the CPU; cpu mode rewrites them only when
  the camera moves, naive every frame: ``rgraph.vk.scene_naive`` copies naive mode's tables to
  device memory at the start of each frame), naive mode's per-object draw commands, and the
  deformable meshes' positions (deformed on the CPU every frame); their normals and tangents
  are computed on the GPU (``rgraph.vk.scene_deform``: ``record_frame`` at the start of the
  frame's first scene batch on the graphics queue), into the vertex buffers the draws bind.
- skinning (bindings 7-9, ``rgraph.vk.skin_gpu.SkinGPU``): joints and weights (lined up with
  the TLSF-placed rigid vertex buffer), the ring of packed logic states and each set's
  interpolation factor.

Passes use ``set_layout`` (set 0 of their pipeline layouts), ``descriptor_set(frame_set)``,
``vertex_input`` and ``draw(rec, frame_set)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rgraph.memory.tlsf import Tlsf
from rgraph.scene import instances as scene_instances
from rgraph.scene import packing
from rgraph.scene.build import SceneData, load_scene_data
from rgraph.vk.buffer_ranges import check_ranges
from rgraph.vk.device import Device
from rgraph.vk.device_local import DeviceBuffer, DeviceLocal
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.passkit import VertexInput
from rgraph.vk.resources import HostBuffer
from rgraph.vk.scene_modes import draw_mode, naive_way, view_count
from rgraph.vk.skin_gpu import BINDING_BONES, BINDING_SKIN_FRAME, BINDING_SKIN_VERTICES, SkinGPU

(BINDING_FRAME, BINDING_DRAWS, BINDING_MATERIALS, BINDING_SCENE_LIGHTS, BINDING_DECALS, BINDING_VIEWS,
 BINDING_MESHES) = range(7)
_BINDING_NAMES = {BINDING_FRAME: "frame uniform", BINDING_DRAWS: "instance (draw) table",
                  BINDING_MATERIALS: "material table", BINDING_SCENE_LIGHTS: "light table",
                  BINDING_DECALS: "decal table", BINDING_VIEWS: "views uniform", BINDING_MESHES: "mesh table",
                  BINDING_SKIN_VERTICES: "skinned vertex table", BINDING_BONES: "bone table",
                  BINDING_SKIN_FRAME: "skinning frame uniform"}


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
        self.mode = draw_mode(plan)
        self.naive_way = naive_way(plan)
        self.views = view_count(plan)
        self.ipd = float(plan.get("params", {}).get("views.ipd", scene_instances.DEFAULT_IPD))
        self.extent: tuple[int, int] = tuple(plan.get("size") or (64, 64))  # type: ignore[assignment]
        self.plan_logic_hz = plan.get("logic_hz")  # skinning's logic rate (default 60 Hz)
        self.skin_threads = int(plan.get("params", {}).get("skin.threads", 1))
        self.skin_worker = str(plan.get("params", {}).get("skin.worker", "process"))
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
        self._submit_once = submit_once
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
        # geometry: every rigid mesh's vertices and every mesh's indices suballocated (TLSF, in
        # vertex / index units) from one device-local buffer each; deformable vertices per set
        # in host memory
        vertex_space, index_space = Tlsf(0, growable=True), Tlsf(0, growable=True)
        placed_vertices, placed_indices, calls = [], [], []
        deform_base = 0
        self._deform_layout: list[tuple[Any, int]] = []  # (mesh, vertex offset) in the per-set buffers
        skinned: list[tuple[Any, int]] = []  # (mesh, first vertex in the rigid vertex buffer)
        for mesh in data.meshes:
            count = mesh.data.triangle_count * 3
            first_index = index_space.allocate(count, 1)
            placed_indices.append((first_index, mesh.data.indices.reshape(-1)))
            if mesh.deformer is None:
                base = vertex_space.allocate(mesh.data.vertex_count, 1)
                if mesh.animator is not None:
                    skinned.append((mesh, base))
                placed_vertices.append((base, mesh.data))
                calls.append(DrawCall(False, count, first_index, base, mesh.instances, mesh.first_draw))
            else:
                self._deform_layout.append((mesh, deform_base))
                calls.append(DrawCall(True, count, first_index, deform_base, mesh.instances, mesh.first_draw))
                deform_base += mesh.data.vertex_count
        self.calls = calls
        index_array = np.zeros(index_space.size, dtype=np.uint32)
        for first, values in placed_indices:
            index_array[first:first + len(values)] = values
        vertex_array = np.zeros((vertex_space.size, packing.VERTEX_BYTES // 4), dtype=np.float32)
        for base, mesh_data in placed_vertices:
            vertex_array[base:base + mesh_data.vertex_count, 0:3] = mesh_data.positions
            vertex_array[base:base + mesh_data.vertex_count, 3:6] = mesh_data.normals
        index_bytes, vertex_bytes = index_array.tobytes(), vertex_array.tobytes()
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
        gpu = self.mode == "gpu"
        instances = scene_instances.instance_bytes(data) if gpu else b""
        meshes = scene_instances.mesh_rows(calls)
        if gpu:
            self.instance_buffer = self._device_buffer(len(instances), storage)
            uploads.append((self.instance_buffer, instances))
        self.meshes_buffer = self._device_buffer(len(meshes), storage)
        uploads.append((self.meshes_buffer, meshes))
        self._upload(submit_once, [(b, d) for b, d in uploads if d])
        self.skin = SkinGPU(self.device, data, self.sets, skinned, vertex_space.size,
                            float(self.plan_logic_hz) if self.plan_logic_hz else 60.0,
                            threads=self.skin_threads, worker=self.skin_worker)

        self.frame_buffers = [self._host_buffer(packing.FRAME_BYTES, v.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT)
                              for _ in range(self.sets)]
        draws_size = len(instances) if gpu else len(packing.draws_bytes(data, 0))
        self.naive = None  # rgraph.vk.scene_naive.NaiveTables (draw.mode=naive)
        if self.mode == "naive":
            from rgraph.vk.scene_naive import NaiveTables

            self.naive = NaiveTables(self.sets, draws_size, data.draw_count, device_buffer=self._device_buffer,
                                     host_buffer=self._host_buffer, direct=self.naive_way == "direct")
            self.draw_buffers = self.naive.host_draws
        else:
            self.draw_buffers = [] if gpu else [self._host_buffer(draws_size, storage) for _ in range(self.sets)]
        views_size = scene_instances.views_size(self.views)
        self.view_buffers = [self._host_buffer(views_size, v.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT)
                             for _ in range(self.sets)]
        self.naive_buffers = self.naive.host_commands if self.naive is not None else []
        decals_size = max(len(data.decals), 1) * packing.DECAL_BYTES
        self.decal_buffers = [self._host_buffer(decals_size, storage) for _ in range(self.sets)]
        if deform_base:
            from rgraph.vk.scene_deform import DeformGPU, DeformPart

            parts = [DeformPart(mesh.data, mesh.deformer.topology, base, mesh.deformer)
                     for mesh, base in self._deform_layout]
            self.deform = DeformGPU(self.device, self.sets, parts, device_buffer=self._device_buffer,
                                    host_buffer=self._host_buffer, upload=lambda ups: self._upload(submit_once, ups))
        self._make_descriptors(materials_size=len(materials), lights_size=len(scene_lights), draws_size=draws_size,
                               decals_size=decals_size, views_size=views_size, meshes_size=len(meshes))
        from rgraph.vk.scene_frame import SceneFrames

        self.frames = SceneFrames(self)
        for s in range(self.sets):
            self.update(0, s)

    def _upload(self, submit_once: Any, uploads: list[tuple[DeviceBuffer, bytes]]) -> None:
        self._device_local.upload(submit_once, uploads)

    def _make_descriptors(self, *, materials_size: int, lights_size: int, draws_size: int, decals_size: int,
                          views_size: int, meshes_size: int) -> None:
        v = vk()
        dev = self.device.handle
        ubo, ssbo = v.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
        kinds = [(BINDING_FRAME, ubo), (BINDING_DRAWS, ssbo), (BINDING_MATERIALS, ssbo),
                 (BINDING_SCENE_LIGHTS, ssbo), (BINDING_DECALS, ssbo), (BINDING_VIEWS, ubo), (BINDING_MESHES, ssbo),
                 (BINDING_SKIN_VERTICES, ssbo), (BINDING_BONES, ssbo), (BINDING_SKIN_FRAME, ubo)]
        bindings = [v.VkDescriptorSetLayoutBinding(binding=b, descriptorType=t, descriptorCount=1,
                                                   stageFlags=v.VK_SHADER_STAGE_ALL) for b, t in kinds]
        self.set_layout = v.vkCreateDescriptorSetLayout(dev, v.VkDescriptorSetLayoutCreateInfo(
            bindingCount=len(bindings), pBindings=bindings), None)
        sizes = [v.VkDescriptorPoolSize(type=ubo, descriptorCount=3 * self.sets),
                 v.VkDescriptorPoolSize(type=ssbo, descriptorCount=7 * self.sets)]
        self._pool = v.vkCreateDescriptorPool(dev, v.VkDescriptorPoolCreateInfo(
            maxSets=self.sets, poolSizeCount=len(sizes), pPoolSizes=sizes), None)
        self._sets = list(v.vkAllocateDescriptorSets(dev, v.VkDescriptorSetAllocateInfo(
            descriptorPool=self._pool, descriptorSetCount=self.sets, pSetLayouts=[self.set_layout] * self.sets)))
        for s in range(self.sets):
            sources = [(BINDING_FRAME, ubo, self.frame_buffers[s].handle, packing.FRAME_BYTES),
                       (BINDING_DRAWS, ssbo, self._draws_of(s).handle, draws_size),
                       (BINDING_MATERIALS, ssbo, self.materials_buffer.handle, materials_size),
                       (BINDING_SCENE_LIGHTS, ssbo, self.scene_lights_buffer.handle, lights_size),
                       (BINDING_DECALS, ssbo, self.decal_buffers[s].handle, decals_size),
                       (BINDING_VIEWS, ubo, self.view_buffers[s].handle, views_size),
                       (BINDING_MESHES, ssbo, self.meshes_buffer.handle, meshes_size)]
            skin = [*self.skin.descriptors(), self.skin.frame_descriptor(s)]
            sources += [(b, ubo if kind == "uniform" else ssbo, buf.handle, size) for b, kind, buf, size in skin]
            if s == 0:
                limits = self.device.properties.limits
                check_ranges([(_BINDING_NAMES.get(b, f"binding {b}"), t == ubo, size) for b, t, _h, size in sources],
                             int(limits.maxStorageBufferRange), int(limits.maxUniformBufferRange),
                             self.data.draw_count)
            infos = [v.VkDescriptorBufferInfo(buffer=h, offset=0, range=size) for _b, _t, h, size in sources]
            writes = [v.VkWriteDescriptorSet(dstSet=self._sets[s], dstBinding=b, descriptorCount=1, descriptorType=t,
                                             pBufferInfo=[info])
                      for (b, t, _h, _size), info in zip(sources, infos, strict=True)]
            v.vkUpdateDescriptorSets(dev, len(writes), writes, 0, None)

    def _draws_of(self, frame_set: int) -> Any:
        """The buffer binding 1 reads: the persistent instances (gpu), the device copy of the
        host-written Draws (naive), the host-written Draws (cpu)."""
        if self.mode == "gpu":
            return self.instance_buffer
        return self.naive.draws[frame_set] if self.naive is not None else self.draw_buffers[frame_set]

    # ----------------------------------------------------------------- per frame
    def update(self, frame: int, frame_set: int) -> None:
        """Write set ``frame_set``'s host memory for ``frame`` (its previous use has finished):
        ``rgraph.vk.scene_frame.SceneFrames.update``. ``draw.mode=gpu`` writes no per-object
        data (the instances are persistent); ``naive`` culls every object on the CPU and
        writes one draw command per object."""
        self.frames.update(frame, frame_set)

    def frame_update(self) -> Any:
        """``update`` as the frame loop calls it during one run (``SceneFrames.frame_update``)."""
        return self.frames.frame_update()

    def prepare(self, frame: int) -> None:
        """Right after the submits of the frame before content frame ``frame``: write what of
        it can be written ahead (``SceneFrames.prepare``)."""
        self.frames.prepare(frame)

    def attach_logic(self, logic: Any) -> None:
        """Take scene time, deformable positions and bones from ``logic`` (a started-on-demand
        ``rgraph.vk.runtime.logic.LogicThread`` whose step is ``logic_step`` and whose lock is
        ``lock``)."""
        self.logic = logic
        if self.skin is not None:
            self.skin.use_logic(logic.hz)  # skinning's logic ticks are this thread's (a worker process may start)
        self.ticks_taken = [None] * self.sets
        self.alpha_range = [1.0, 0.0]  # (min, max) of the alphas used, for the run's report

    @property
    def lock(self) -> Any:
        """The lock the logic thread publishes states under (ring slots change hands under it)."""
        return self.frames.lock

    def logic_step(self, seconds: float) -> Any:
        """One logic tick at scene time ``seconds`` (the logic thread): (deformable slot, bones
        slot) of the ring slots it wrote (``SceneFrames.logic_step``)."""
        return self.frames.logic_step(seconds)

    def record_frame(self, cb: Any, frame_set: int) -> None:
        """The scene's per-frame GPU work before the frame's draws, with its barriers: the
        deformable vertices' compute pass, draw.mode=naive's table copies (nothing otherwise)."""
        if self.deform is not None:
            self.deform.record(cb, frame_set)
        if self.naive is not None:
            self.naive.record(cb, frame_set)

    @property
    def records_per_frame(self) -> bool:
        """The frame's command buffers are recorded again every frame (draw.mode=naive, direct
        draws of the objects the CPU found visible: ``rgraph.vk.runtime.commands.rerecord``)."""
        return self.naive is not None and self.naive.direct

    def refresh_instances(self) -> None:
        """After instances moved (``SceneMesh.positions`` changed in ``self.data``): drop the
        per-scene caches and, with draw.mode=gpu, upload the persistent instance table again -
        only when something changed, never per frame. The upload waits for the device to be
        idle (frames in flight read the table), so it suits rare changes."""
        for cache in ("_instance_arrays", "_packed_draw_table", "_frame_cache", "_views_cache"):
            self.data.__dict__.pop(cache, None)
        self.frames.forget_camera()  # the camera-relative tables are written again at the next update
        if self.mode == "gpu":
            vk().vkDeviceWaitIdle(self.device.handle)
            self._upload(self._submit_once, [(self.instance_buffer, scene_instances.instance_bytes(self.data))])

    def draw(self, rec: Any, frame_set: int, share: Any = None, args: Any = None) -> None:
        """Bind vertex and index buffers and record the scene's draws.

        - ``args`` (the graph buffer ``draw_args`` of ``draw_cull``, draw.mode=gpu): one
          ``vkCmdDrawIndexedIndirectCount`` over the culled commands (count at offset 0,
          commands from offset 16), then the deformable meshes directly;
        - draw.mode=naive: one ``vkCmdDrawIndexed`` per CPU-visible object (``draw.naive=direct``,
          recorded per frame) or one ``vkCmdDrawIndexedIndirect`` per object (``indirect``);
        - otherwise one drawIndexed per mesh (instances = the mesh's instances, firstInstance =
          its first draw index).
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
        if self.naive is not None and not self.naive.recorded[frame_set]:
            raise ExecutionError("draw.mode=naive: scene drawn before the frame's table copies were recorded (the draw "
                                 "is not on the graphics queue after the frame's first scene batch)")
        if args is not None and self.mode == "gpu" and share is None:
            rec.bind_vertex_buffers([self.vertex_buffer.handle])
            bound = self.vertex_buffer.handle
            rec.draw_indexed_indirect_count(args, 16, args, 0, self.draw_count)
            calls = [c for c in calls if c.deformable]
        for call in calls:
            want = self.deform.vertex_buffers[frame_set].handle if call.deformable else self.vertex_buffer.handle
            if want is not bound:
                rec.bind_vertex_buffers([want])
                bound = want
            if self.mode == "naive" and not call.deformable:
                self.naive.draw(rec, call, frame_set)
                continue
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
