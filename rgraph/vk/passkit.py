"""What a pass implementation gets at setup: its plan pass, params, views, pipelines, scene.

``PassSetup`` owns every object it creates for the implementation (``own``) and destroys
them after the implementation's ``destroy``. Pipelines are built against the render pass
the runtime made for the pass (raster passes): its attachments are the pass's attachment
accesses in plan order, colour first, then depth; initial and final layouts are the plan's.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any

from rgraph import formats
from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.resources import HostBuffer, Resource, ResourceSet, destroy_owned
from rgraph.vk.shaders import compile_shader, find_shader

DESCRIPTOR_KINDS = ("sampled", "storage_image", "storage_buffer", "uniform_buffer")


@dataclass(frozen=True)
class Binding:
    """One descriptor binding of set ``set`` (see ``PassSetup.descriptors``).

    Exactly one source: ``resource`` (a plan resource this pass accesses; images may narrow
    ``mips``/``layers``, storage images must name one mip), or ``buffers`` (one
    ``(VkBuffer, bytes)`` per frame-in-flight set, or one for all sets), for data the
    implementation owns (host-visible uniforms, lookup tables).
    """

    binding: int
    kind: str  # one of DESCRIPTOR_KINDS
    resource: str | None = None
    mips: tuple[int, int] | None = None
    layers: tuple[int, int] | None = None
    array: bool = False  # a 2D-array view (sampler2DArray / image2DArray) instead of 2D
    sampler: str = "linear"  # sampled images: "linear" or "nearest" (clamp to edge)
    buffers: tuple[tuple[Any, int], ...] | None = None


@dataclass
class DescriptorSets:
    layout: Any
    sets: list[Any]  # one per frame-in-flight set

    def __getitem__(self, frame_set: int) -> Any:
        return self.sets[frame_set]


@dataclass
class Pipeline:
    pipeline: Any
    layout: Any
    push_stages: int = 0
    bind_point: int = 0


@dataclass
class VertexInput:
    """Vertex buffer layout: ``stride`` bytes per vertex; attributes (location, format name, offset)."""

    stride: int
    attributes: list[tuple[int, str, int]] = field(default_factory=list)


_BLENDS = {
    None: None,
    "add": ("ONE", "ONE", "ONE", "ONE"),
    "alpha": ("SRC_ALPHA", "ONE_MINUS_SRC_ALPHA", "ONE", "ONE_MINUS_SRC_ALPHA"),
    "premultiplied": ("ONE", "ONE_MINUS_SRC_ALPHA", "ONE", "ONE_MINUS_SRC_ALPHA"),
}


class PassParams(dict):
    """A pass's params (the graph's, then its own); remembers the names looked up, so a sweep
    knows which passes a knob reaches (``RunResult.params_read``)."""

    def __init__(self, values: dict[str, Any]) -> None:
        super().__init__(values)
        self.read: set[str] = set()

    def __getitem__(self, name: str) -> Any:
        self.read.add(name)
        return super().__getitem__(name)

    def get(self, name: str, default: Any = None) -> Any:
        self.read.add(name)
        return super().get(name, default)

    def __contains__(self, name: object) -> bool:
        if isinstance(name, str):
            self.read.add(name)
        return super().__contains__(name)


def descriptor_types() -> dict[str, int]:
    """Binding kind (``Binding.kind``) -> VkDescriptorType, for every pass runtime."""
    v = vk()
    return {"sampled": v.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
            "storage_image": v.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
            "storage_buffer": v.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
            "uniform_buffer": v.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
            "accel": v.VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR}


class PassSetup:
    """Everything an implementation may use to prepare itself; see ``rgraph.impl``."""

    def __init__(self, device: Device, plan: dict, plan_pass: dict, resources: ResourceSet, *,
                 sets: int, render_pass: Any = None, extent: tuple[int, int] | None = None,
                 layers: int = 1, scene: Any = None, samplers: dict[str, Any] | None = None,
                 accels: Any = None) -> None:
        self.device = device
        self.plan = plan
        self.plan_pass = plan_pass
        self.name: str = plan_pass["name"]
        self.kind: str = plan_pass["kind"]
        self.resources = resources
        self.sets = sets
        self.render_pass = render_pass
        self.size: tuple[int, int] = tuple(plan.get("size") or (64, 64))  # type: ignore[assignment]
        self.extent: tuple[int, int] = extent or self.size
        self.layers = layers  # framebuffer layers of a raster pass (layered attachments)
        self.params = PassParams({**plan.get("params", {}), **plan_pass.get("params", {})})
        self.features: dict[str, Any] = dict(plan.get("features", {}))
        self._scene = scene
        self.uses_scene = False  # set by the first ``scene`` lookup (rgraph.vk.runtime.commands)
        self.accels = accels  # rgraph.vk.accel.AccelSet of the plan's accels (None: none)
        self._samplers = samplers if samplers is not None else {}
        self._objects: list[tuple[str, Any]] = []
        self._host_buffers: list[HostBuffer] = []
        self._accesses = {a["resource"]: a for a in plan_pass["accesses"]}
        self._res_plan = {r["name"]: r for r in plan["resources"]}

    @property
    def max_uniform_range(self) -> int:
        """The device's ``maxUniformBufferRange``: the most bytes one uniform-buffer descriptor
        binds (a larger plan buffer is bound up to it; unknown limits: no cap)."""
        props = getattr(self.device, "properties", None)
        return int(props.limits.maxUniformBufferRange) if props is not None else (1 << 32) - 1

    # ------------------------------------------------------------- plan lookups
    @property
    def scene(self) -> Any:
        """The run's ``rgraph.vk.scene_gpu.SceneGPU`` (built on first use, shared by all passes)."""
        self.uses_scene = True
        if callable(self._scene):
            self._scene = self._scene()
        if self._scene is None:
            raise ExecutionError(f"pass {self.name!r}: the plan has no scene")
        return self._scene

    def param(self, name: str, default: Any = None) -> Any:
        return self.params.get(name, default)

    def has(self, resource: str) -> bool:
        """Whether this pass accesses ``resource`` (an optional read may have been dropped)."""
        return resource in self._accesses

    def access(self, resource: str) -> dict:
        try:
            return self._accesses[resource]
        except KeyError:
            raise ExecutionError(f"pass {self.name!r} does not access {resource!r}") from None

    def resource(self, resource: str, frame_set: int = 0) -> Resource:
        self.access(resource)
        return self.resources.get(resource, frame_set)

    def resource_plan(self, resource: str) -> dict:
        return self._res_plan[resource]

    def extent_of(self, resource: str, mip: int = 0) -> tuple[int, int]:
        w, h = self._res_plan[resource]["extent"][:2]
        return max(1, w >> mip), max(1, h >> mip)

    def image_view(self, resource: str, frame_set: int, *, mips: tuple[int, int] | None = None,
                   layers: tuple[int, int] | None = None, array: bool = False, depth_aspect: bool | None = None) -> Any:
        a = self.access(resource)
        r = self.resources.get(resource, frame_set)
        mips = mips or tuple(a["subresource"]["mips"])
        layers = layers or tuple(a["subresource"]["layers"])
        has_depth = formats.lookup(r.plan["format"]).has_depth
        aspect = vk().VK_IMAGE_ASPECT_DEPTH_BIT if (has_depth if depth_aspect is None else depth_aspect) else None
        return self.resources.view(r, mips, layers, aspect, array=array)

    def buffer(self, resource: str, frame_set: int) -> tuple[Any, int]:
        r = self.resource(resource, frame_set)
        return r.handle, int(r.plan["size_bytes"] or r.plan["bytes"])

    # ------------------------------------------------------------- ownership
    def own(self, destroy: str, handle: Any) -> Any:
        """Destroy ``handle`` with ``vk.<destroy>`` when the run ends."""
        self._objects.append((destroy, handle))
        return handle

    def host_buffer(self, size: int, usage: str | int = "uniform", allocate_flags: int = 0) -> HostBuffer:
        """A mapped, coherent host-visible buffer (``usage``: uniform, storage, vertex, index or
        flags; ``allocate_flags``: VkMemoryAllocateFlags of its memory, e.g. device address)."""
        v = vk()
        flags = usage if isinstance(usage, int) else {
            "uniform": v.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "storage": v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
            "vertex": v.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, "index": v.VK_BUFFER_USAGE_INDEX_BUFFER_BIT}[usage]
        buf = HostBuffer.create(self.device, size, flags, allocate_flags=allocate_flags)
        self._host_buffers.append(buf)
        return buf

    def device_buffer(self, payload: bytes, usage: str | int = "storage") -> tuple[Any, int]:
        """(handle, size) of a DEVICE_LOCAL buffer holding ``payload`` (filled once, now), owned
        by the pass; ``usage`` as ``host_buffer``."""
        from rgraph.vk.static_buffer import upload_static

        v = vk()
        flags = usage if isinstance(usage, int) else {
            "uniform": v.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, "storage": v.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT}[usage]
        handle, memory, size = upload_static(self.device, payload, flags)
        self.own("vkFreeMemory", memory)  # destroyed newest first: the buffer, then its memory
        self.own("vkDestroyBuffer", handle)
        return handle, size

    def sampler(self, kind: str = "linear") -> Any:
        """A shared clamp-to-edge sampler: ``linear`` or ``nearest``."""
        if kind not in self._samplers:
            v = vk()
            filt = v.VK_FILTER_LINEAR if kind == "linear" else v.VK_FILTER_NEAREST
            mip = v.VK_SAMPLER_MIPMAP_MODE_LINEAR if kind == "linear" else v.VK_SAMPLER_MIPMAP_MODE_NEAREST
            edge = v.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE
            self._samplers[kind] = v.vkCreateSampler(self.device.handle, v.VkSamplerCreateInfo(
                magFilter=filt, minFilter=filt, mipmapMode=mip, addressModeU=edge, addressModeV=edge,
                addressModeW=edge, maxLod=1000.0), None)
        return self._samplers[kind]

    # ------------------------------------------------------------- shaders and pipelines
    def shader(self, path: str, defines: dict[str, Any] | None = None) -> Any:
        """A VkShaderModule from ``shaders/<path>`` compiled by glslc (cached by content), with the
        scene's draw-mode and view defines (``rgraph.vk.scene_modes.scene_defines``)."""
        from rgraph.vk.scene_modes import scene_defines

        compiled = compile_shader(find_shader(path), defines={**scene_defines(self.plan, self.device), **(defines or {})})
        v = vk()
        module = v.vkCreateShaderModule(self.device.handle, v.VkShaderModuleCreateInfo(
            codeSize=len(compiled.spirv), pCode=compiled.spirv), None)
        return self.own("vkDestroyShaderModule", module)

    def descriptors(self, bindings: list[Binding], extra_layouts: int = 0) -> DescriptorSets:
        """A set layout and one descriptor set per frame-in-flight set, written once."""
        v = vk()
        dev = self.device.handle
        types = descriptor_types()
        for b in bindings:
            if b.kind not in types:
                raise ExecutionError(f"pass {self.name!r}: descriptor kind {b.kind!r} not one of {DESCRIPTOR_KINDS}")
        layout_bindings = [v.VkDescriptorSetLayoutBinding(binding=b.binding, descriptorType=types[b.kind],
                                                          descriptorCount=1, stageFlags=v.VK_SHADER_STAGE_ALL)
                           for b in bindings]
        layout = self.own("vkDestroyDescriptorSetLayout", v.vkCreateDescriptorSetLayout(
            dev, v.VkDescriptorSetLayoutCreateInfo(bindingCount=len(layout_bindings),
                                                   pBindings=layout_bindings or None), None))
        if not bindings:
            return DescriptorSets(layout, [])
        counts: dict[int, int] = {}
        for b in bindings:
            counts[types[b.kind]] = counts.get(types[b.kind], 0) + self.sets
        sizes = [v.VkDescriptorPoolSize(type=t, descriptorCount=n) for t, n in counts.items()]
        pool = self.own("vkDestroyDescriptorPool", v.vkCreateDescriptorPool(dev, v.VkDescriptorPoolCreateInfo(
            maxSets=self.sets, poolSizeCount=len(sizes), pPoolSizes=sizes), None))
        sets = v.vkAllocateDescriptorSets(dev, v.VkDescriptorSetAllocateInfo(
            descriptorPool=pool, descriptorSetCount=self.sets, pSetLayouts=[layout] * self.sets))
        for s in range(self.sets):
            writes, keep = [], []
            for b in bindings:
                info: Any
                if b.kind in ("sampled", "storage_image"):
                    if b.resource is None:
                        raise ExecutionError(f"pass {self.name!r}: image binding {b.binding} names no resource")
                    a = self.access(b.resource)
                    mips = b.mips or tuple(a["subresource"]["mips"])
                    if b.kind == "storage_image" and mips[1] - mips[0] != 1:
                        mips = (mips[0], mips[0] + 1)
                    view = self.image_view(b.resource, s, mips=mips, layers=b.layers, array=b.array)
                    layout_value = names.layout(a["layout"])
                    if b.kind == "sampled":
                        info = v.VkDescriptorImageInfo(sampler=self.sampler(b.sampler), imageView=view,
                                                       imageLayout=layout_value)
                    else:
                        info = v.VkDescriptorImageInfo(imageView=view, imageLayout=layout_value)
                    writes.append(v.VkWriteDescriptorSet(dstSet=sets[s], dstBinding=b.binding, descriptorCount=1,
                                                         descriptorType=types[b.kind], pImageInfo=[info]))
                else:
                    if b.resource is not None:
                        handle, size = self.buffer(b.resource, s)
                    elif b.buffers:
                        handle, size = b.buffers[s] if len(b.buffers) > 1 else b.buffers[0]
                    else:
                        raise ExecutionError(f"pass {self.name!r}: buffer binding {b.binding} has no buffer")
                    if b.kind == "uniform_buffer":  # a larger range is invalid (VUID-VkWriteDescriptorSet-00332)
                        size = min(int(size), self.max_uniform_range)
                    info = v.VkDescriptorBufferInfo(buffer=handle, offset=0, range=int(size))
                    writes.append(v.VkWriteDescriptorSet(dstSet=sets[s], dstBinding=b.binding, descriptorCount=1,
                                                         descriptorType=types[b.kind], pBufferInfo=[info]))
                keep.append(info)
            v.vkUpdateDescriptorSets(dev, len(writes), writes, 0, None)
        return DescriptorSets(layout, list(sets))

    def _pipeline_layout(self, set_layouts: list[Any], push_constant_bytes: int, push_stages: int) -> Any:
        v = vk()
        ranges = ([v.VkPushConstantRange(stageFlags=push_stages, offset=0, size=push_constant_bytes)]
                  if push_constant_bytes else [])
        return self.own("vkDestroyPipelineLayout", v.vkCreatePipelineLayout(self.device.handle, v.VkPipelineLayoutCreateInfo(
            setLayoutCount=len(set_layouts), pSetLayouts=set_layouts or None,
            pushConstantRangeCount=len(ranges), pPushConstantRanges=ranges or None), None))

    def compute_pipeline(self, shader: str, set_layouts: list[Any], *, defines: dict[str, Any] | None = None,
                         push_constant_bytes: int = 0) -> Pipeline:
        v = vk()
        module = self.shader(shader, defines)
        layout = self._pipeline_layout(set_layouts, push_constant_bytes, v.VK_SHADER_STAGE_COMPUTE_BIT)
        stage = v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_COMPUTE_BIT, module=module, pName="main")
        pipeline = v.vkCreateComputePipelines(self.device.handle, None, 1, [
            v.VkComputePipelineCreateInfo(stage=stage, layout=layout)], None)[0]
        return Pipeline(self.own("vkDestroyPipeline", pipeline), layout, v.VK_SHADER_STAGE_COMPUTE_BIT,
                        v.VK_PIPELINE_BIND_POINT_COMPUTE)

    def graphics_pipeline(self, vertex: str, fragment: str | None, set_layouts: list[Any], *,
                          defines: dict[str, Any] | None = None, push_constant_bytes: int = 0,
                          vertex_input: VertexInput | None = None, topology: str = "TRIANGLE_LIST",
                          cull: str = "NONE", front_face: str = "COUNTER_CLOCKWISE",
                          depth_test: bool = False, depth_write: bool = False, depth_compare: str = "GREATER_OR_EQUAL",
                          depth_bias: tuple[float, float] | None = None, blend: list[str | None] | None = None,
                          extent: tuple[int, int] | None = None) -> Pipeline:
        """A pipeline for this pass's render pass. ``blend`` per colour attachment: None, add,
        alpha, premultiplied. Viewport and scissor are the pass extent (static)."""
        v = vk()
        if self.render_pass is None:
            raise ExecutionError(f"pass {self.name!r}: graphics pipelines need a raster pass")
        stages_all = v.VK_SHADER_STAGE_VERTEX_BIT | v.VK_SHADER_STAGE_FRAGMENT_BIT
        layout = self._pipeline_layout(set_layouts, push_constant_bytes, stages_all)
        stages = [v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_VERTEX_BIT,
                                                    module=self.shader(vertex, defines), pName="main")]
        if fragment is not None:
            stages.append(v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_FRAGMENT_BIT,
                                                            module=self.shader(fragment, defines), pName="main"))
        if vertex_input is not None:
            vb = [v.VkVertexInputBindingDescription(binding=0, stride=vertex_input.stride,
                                                    inputRate=v.VK_VERTEX_INPUT_RATE_VERTEX)]
            va = [v.VkVertexInputAttributeDescription(location=loc, binding=0, format=names.format_value(fmt),
                                                      offset=off) for loc, fmt, off in vertex_input.attributes]
        else:
            vb, va = [], []
        vis = v.VkPipelineVertexInputStateCreateInfo(
            vertexBindingDescriptionCount=len(vb), pVertexBindingDescriptions=vb or None,
            vertexAttributeDescriptionCount=len(va), pVertexAttributeDescriptions=va or None)
        assembly = v.VkPipelineInputAssemblyStateCreateInfo(topology=getattr(v, f"VK_PRIMITIVE_TOPOLOGY_{topology}"))
        w, h = extent or self.extent
        viewport = v.VkViewport(x=0, y=0, width=float(w), height=float(h), minDepth=0.0, maxDepth=1.0)
        from rgraph.vk.multi.tiles import scissor_rect

        scissor = scissor_rect(self.plan_pass, w, h)  # a sort-first tile, else all of it
        vps = v.VkPipelineViewportStateCreateInfo(viewportCount=1, pViewports=[viewport], scissorCount=1,
                                                  pScissors=[scissor])
        raster = v.VkPipelineRasterizationStateCreateInfo(
            polygonMode=v.VK_POLYGON_MODE_FILL, cullMode=getattr(v, f"VK_CULL_MODE_{cull}"
                                                                 + ("_BIT" if cull in ("FRONT", "BACK") else "")),
            frontFace=getattr(v, f"VK_FRONT_FACE_{front_face}"), lineWidth=1.0,
            depthBiasEnable=v.VK_TRUE if depth_bias else v.VK_FALSE,
            depthBiasConstantFactor=depth_bias[0] if depth_bias else 0.0,
            depthBiasSlopeFactor=depth_bias[1] if depth_bias else 0.0)
        ms = v.VkPipelineMultisampleStateCreateInfo(rasterizationSamples=v.VK_SAMPLE_COUNT_1_BIT)
        ds = v.VkPipelineDepthStencilStateCreateInfo(
            depthTestEnable=v.VK_TRUE if depth_test else v.VK_FALSE,
            depthWriteEnable=v.VK_TRUE if depth_write else v.VK_FALSE,
            depthCompareOp=getattr(v, f"VK_COMPARE_OP_{depth_compare}"))
        colors = [a for a in self.plan_pass["accesses"] if a["usage"].startswith("color_attachment")]
        blend = blend if blend is not None else [None] * len(colors)
        if len(blend) != len(colors):
            raise ExecutionError(f"pass {self.name!r}: {len(blend)} blend states for {len(colors)} colour attachments")
        mask = (v.VK_COLOR_COMPONENT_R_BIT | v.VK_COLOR_COMPONENT_G_BIT | v.VK_COLOR_COMPONENT_B_BIT
                | v.VK_COLOR_COMPONENT_A_BIT)
        states = []
        for mode in blend:
            f = _BLENDS[mode]
            if f is None:
                states.append(v.VkPipelineColorBlendAttachmentState(blendEnable=v.VK_FALSE, colorWriteMask=mask))
            else:
                factor = [getattr(v, f"VK_BLEND_FACTOR_{x}") for x in f]
                states.append(v.VkPipelineColorBlendAttachmentState(
                    blendEnable=v.VK_TRUE, srcColorBlendFactor=factor[0], dstColorBlendFactor=factor[1],
                    colorBlendOp=v.VK_BLEND_OP_ADD, srcAlphaBlendFactor=factor[2], dstAlphaBlendFactor=factor[3],
                    alphaBlendOp=v.VK_BLEND_OP_ADD, colorWriteMask=mask))
        cbs = v.VkPipelineColorBlendStateCreateInfo(attachmentCount=len(states), pAttachments=states or None)
        info = v.VkGraphicsPipelineCreateInfo(
            stageCount=len(stages), pStages=stages, pVertexInputState=vis, pInputAssemblyState=assembly,
            pViewportState=vps, pRasterizationState=raster, pMultisampleState=ms, pDepthStencilState=ds,
            pColorBlendState=cbs, layout=layout, renderPass=self.render_pass, subpass=0)
        pipeline = v.vkCreateGraphicsPipelines(self.device.handle, None, 1, [info], None)[0]
        return Pipeline(self.own("vkDestroyPipeline", pipeline), layout, stages_all, v.VK_PIPELINE_BIND_POINT_GRAPHICS)

    # ------------------------------------------------------------- teardown
    def destroy(self) -> None:
        destroy_owned(self.device, self._objects, self._host_buffers)


def pack(fmt: str, *values: Any) -> bytes:
    """``struct.pack`` little-endian, for push constants and uniform blocks."""
    return struct.pack("<" + fmt, *values)
