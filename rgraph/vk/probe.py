"""The probe on the device: a registered ``PassImpl`` (``PROBE``) built on ``PassSetup``.

What each pass computes is ``rgraph.probe.semantics``; its shaders come from
``rgraph.vk.probe_glsl``; the data check of its outputs is ``rgraph.probe.check``.
Everything is created once; ``record`` only records.
"""

from __future__ import annotations

import hashlib
import tempfile
from pathlib import Path
from typing import Any

from rgraph import formats
from rgraph.impl import PassImpl, register
from rgraph.probe.semantics import analyze, mip_extent, subresources
from rgraph.probe.values import HEADER_WORDS, has_header, modulus
from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.passkit import PassSetup, descriptor_types
from rgraph.vk.probe_glsl import ProbeShaders, generate
from rgraph.vk.record_context import RecordContext
from rgraph.vk.resources import HostBuffer, Resource
from rgraph.vk.runtime.staging import fill_bytes, image_copy_regions

#: The registered name of the probe implementation: passes without ``impl:`` run it.
PROBE = "rgraph.probe"

_GENERATED = Path(tempfile.gettempdir()) / "rgraph-probe-glsl"


def compile_glsl(source: str, stage: str) -> bytes:
    """Compile generated GLSL through the shader cache (written under a content-hashed name)."""
    from rgraph.vk.shaders import compile_shader

    _GENERATED.mkdir(parents=True, exist_ok=True)
    digest = hashlib.sha256(source.encode()).hexdigest()[:24]
    path = _GENERATED / f"{digest}.{stage}"
    if not path.exists():
        tmp = path.with_suffix(f".{stage}.tmp")
        tmp.write_text(source)
        tmp.replace(path)
    return compile_shader(path).spirv


def _module(device: Device, spirv: bytes) -> Any:
    v = vk()
    info = v.VkShaderModuleCreateInfo(codeSize=len(spirv), pCode=spirv)
    return v.vkCreateShaderModule(device.handle, info, None)


@register(PROBE)
class Probe(PassImpl):
    """One plan pass executed by the probe, for every frame-in-flight set: the implementation
    of every pass without ``impl:``. It makes its own render passes (one framebuffer per
    layer of a layered attachment, ``owns_render_pass``) and its own descriptor sets (by
    access, as a pass may access one resource twice); ``setup`` owns every object."""

    owns_render_pass = True

    def __init__(self, setup: PassSetup) -> None:
        super().__init__(setup)
        self.device = setup.device
        self.plan = setup.plan
        self.p = setup.plan_pass
        self.resources = setup.resources
        self.sampler = setup.sampler("nearest")
        self.res_plan = {r["name"]: r for r in self.plan["resources"]}
        self.plan_size = setup.size
        self.accels: Any = setup.accels  # rgraph.vk.accel.AccelSet: accel_read bindings (ray queries)
        self.sets: list[Any] = []
        self.framebuffers: list[list[Any]] = []
        self.shaders: ProbeShaders | None = None
        if self.p["kind"] == "transfer":
            self._prepare_transfer()
        else:
            self._prepare_shaders()

    def _prepare_shaders(self) -> None:
        """Shaders and pipeline of a compute or raster pass (ray tracing: ``rgraph.vk.probe_rt``)."""
        self.shaders = generate(self.p, self.res_plan, self.plan_size)
        self._prepare_pipeline()

    # ------------------------------------------------------------------ setup
    def _own(self, destroy: str, handle: Any) -> Any:
        return self.setup.own(destroy, handle)

    def _resource(self, access_index: int, set_index: int) -> Resource:
        return self.resources.get(self.p["accesses"][access_index]["resource"], set_index)

    def _prepare_pipeline(self) -> None:
        v = vk()
        dev = self.device.handle
        sh = self.shaders
        assert sh is not None
        kinds = descriptor_types()
        layout_bindings = [v.VkDescriptorSetLayoutBinding(
            binding=b.binding, descriptorType=kinds[b.kind], descriptorCount=1, stageFlags=v.VK_SHADER_STAGE_ALL)
            for b in sh.bindings]
        self.set_layout = self._own("vkDestroyDescriptorSetLayout", v.vkCreateDescriptorSetLayout(
            dev, v.VkDescriptorSetLayoutCreateInfo(bindingCount=len(layout_bindings),
                                                   pBindings=layout_bindings or None), None))
        self.layout = self._own("vkDestroyPipelineLayout", v.vkCreatePipelineLayout(
            dev, v.VkPipelineLayoutCreateInfo(setLayoutCount=1, pSetLayouts=[self.set_layout]), None))
        if sh.bindings:
            self._allocate_sets([kinds[b.kind] for b in sh.bindings])
            for s in range(self.resources.sets):
                self._write_descriptors(s, kinds)
        modules = {stage: self._own("vkDestroyShaderModule", _module(self.device, compile_glsl(src, stage)))
                   for stage, src in sh.sources.items()}
        if sh.kind == "compute":
            stage = v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_COMPUTE_BIT, module=modules["comp"],
                                                      pName="main")
            self.pipeline = self._own("vkDestroyPipeline", v.vkCreateComputePipelines(
                dev, None, 1, [v.VkComputePipelineCreateInfo(stage=stage, layout=self.layout)], None)[0])
            return
        self._prepare_raster(modules)

    def _allocate_sets(self, types: list[int]) -> None:
        """A pool and one descriptor set of ``self.set_layout`` per frame-in-flight set."""
        v = vk()
        sets = self.resources.sets
        counts: dict[int, int] = {}
        for t in types:
            counts[t] = counts.get(t, 0) + sets
        sizes = [v.VkDescriptorPoolSize(type=t, descriptorCount=n) for t, n in counts.items()]
        self.pool = self._own("vkDestroyDescriptorPool", v.vkCreateDescriptorPool(
            self.device.handle, v.VkDescriptorPoolCreateInfo(maxSets=sets, poolSizeCount=len(sizes), pPoolSizes=sizes),
            None))
        self.sets = v.vkAllocateDescriptorSets(self.device.handle, v.VkDescriptorSetAllocateInfo(
            descriptorPool=self.pool, descriptorSetCount=sets, pSetLayouts=[self.set_layout] * sets))

    def _write_descriptors(self, set_index: int, kinds: dict[str, int]) -> None:
        v = vk()
        writes, keep = [], []
        for b in self.shaders.bindings:
            a = self.p["accesses"][b.access]
            r = self._resource(b.access, set_index)
            if b.kind == "sampled":
                sub = a["subresource"]
                aspect = v.VK_IMAGE_ASPECT_DEPTH_BIT if formats.lookup(r.plan["format"]).has_depth else None
                view = self.resources.view(r, tuple(sub["mips"]), tuple(sub["layers"]), aspect)
                info = v.VkDescriptorImageInfo(sampler=self.sampler, imageView=view,
                                               imageLayout=names.layout(a["layout"]))
                keep.append(info)
                writes.append(v.VkWriteDescriptorSet(dstSet=self.sets[set_index], dstBinding=b.binding,
                                                     descriptorCount=1, descriptorType=kinds[b.kind],
                                                     pImageInfo=[info]))
            elif b.kind == "accel":
                handles = v.ffi.new("VkAccelerationStructureKHR[1]", [self.accels.tlas(a["resource"], set_index)])
                info = v.VkWriteDescriptorSetAccelerationStructureKHR(accelerationStructureCount=1,
                                                                      pAccelerationStructures=handles)
                keep += [handles, info]
                writes.append(v.VkWriteDescriptorSet(pNext=info, dstSet=self.sets[set_index], dstBinding=b.binding,
                                                     descriptorCount=1, descriptorType=kinds[b.kind]))
            elif b.kind == "storage_image":
                view = self.resources.view(r, (b.mip, b.mip + 1), tuple(a["subresource"]["layers"]))
                info = v.VkDescriptorImageInfo(imageView=view, imageLayout=names.layout(a["layout"]))
                keep.append(info)
                writes.append(v.VkWriteDescriptorSet(dstSet=self.sets[set_index], dstBinding=b.binding,
                                                     descriptorCount=1, descriptorType=kinds[b.kind],
                                                     pImageInfo=[info]))
            else:
                size = int(r.plan["size_bytes"] or r.plan["bytes"])
                if b.kind == "uniform_buffer":
                    size = min(size, 65536)
                info = v.VkDescriptorBufferInfo(buffer=r.handle, offset=0, range=size // 4 * 4 or size)
                keep.append(info)
                writes.append(v.VkWriteDescriptorSet(dstSet=self.sets[set_index], dstBinding=b.binding,
                                                     descriptorCount=1, descriptorType=kinds[b.kind],
                                                     pBufferInfo=[info]))
        if writes:
            v.vkUpdateDescriptorSets(self.device.handle, len(writes), writes, 0, None)

    def _prepare_raster(self, modules: dict[str, Any]) -> None:
        v = vk()
        dev = self.device.handle
        sh = self.shaders
        accesses = self.p["accesses"]
        barrier_from_undefined = {b["resource"] for b in self.p["barriers"] if b["src"]["layout"] == "UNDEFINED"}
        attachments, color_refs, depth_ref = [], [], None
        self.clear_values = []
        att_accesses = sh.color_accesses + ([sh.depth_access] if sh.depth_access is not None else [])
        for n, i in enumerate(att_accesses):
            a = accesses[i]
            res = self.res_plan[a["resource"]]
            layout = names.layout(a["layout"])
            usage = a["usage"]
            if usage == "color_attachment":
                load, store = v.VK_ATTACHMENT_LOAD_OP_DONT_CARE, v.VK_ATTACHMENT_STORE_OP_STORE
            elif usage == "color_attachment_blend":
                load, store = v.VK_ATTACHMENT_LOAD_OP_LOAD, v.VK_ATTACHMENT_STORE_OP_STORE
            elif usage == "depth_attachment":
                load = (v.VK_ATTACHMENT_LOAD_OP_CLEAR if a["resource"] in barrier_from_undefined
                        else v.VK_ATTACHMENT_LOAD_OP_LOAD)
                store = v.VK_ATTACHMENT_STORE_OP_STORE
            else:  # depth_read: read-only, no store access
                load, store = v.VK_ATTACHMENT_LOAD_OP_LOAD, v.VK_ATTACHMENT_STORE_OP_NONE
            attachments.append(v.VkAttachmentDescription(
                format=names.format_value(res["format"]), samples=v.VK_SAMPLE_COUNT_1_BIT, loadOp=load, storeOp=store,
                stencilLoadOp=v.VK_ATTACHMENT_LOAD_OP_DONT_CARE, stencilStoreOp=v.VK_ATTACHMENT_STORE_OP_DONT_CARE,
                initialLayout=layout, finalLayout=layout))
            ref = v.VkAttachmentReference(attachment=n, layout=layout)
            if usage.startswith("color"):
                color_refs.append(ref)
                self.clear_values.append(v.VkClearValue(color=v.VkClearColorValue(float32=[0, 0, 0, 0])))
            else:
                depth_ref = ref
                self.clear_values.append(v.VkClearValue(depthStencil=v.VkClearDepthStencilValue(depth=0.0, stencil=0)))
        subpass = v.VkSubpassDescription(
            pipelineBindPoint=v.VK_PIPELINE_BIND_POINT_GRAPHICS, colorAttachmentCount=len(color_refs),
            pColorAttachments=color_refs or None, pDepthStencilAttachment=depth_ref)
        self.render_pass = self._own("vkDestroyRenderPass", v.vkCreateRenderPass(dev, v.VkRenderPassCreateInfo(
            attachmentCount=len(attachments), pAttachments=attachments or None, subpassCount=1, pSubpasses=[subpass],
            dependencyCount=0), None))
        w, h = sh.domain
        for s in range(self.resources.sets):
            per_layer = []
            for layer in range(sh.layer_count):
                views = []
                for i in att_accesses:
                    a = accesses[i]
                    sub = a["subresource"]
                    r = self._resource(i, s)
                    base = sub["layers"][0] + layer
                    aspect = v.VK_IMAGE_ASPECT_DEPTH_BIT if formats.lookup(r.plan["format"]).has_depth else None
                    views.append(self.resources.view(r, tuple(sub["mips"]), (base, base + 1), aspect))
                per_layer.append(self._own("vkDestroyFramebuffer", v.vkCreateFramebuffer(dev, v.VkFramebufferCreateInfo(
                    renderPass=self.render_pass, attachmentCount=len(views), pAttachments=views or None,
                    width=w, height=h, layers=1), None)))
            self.framebuffers.append(per_layer)
        stages = [v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_VERTEX_BIT, module=modules["vert"],
                                                    pName="main"),
                  v.VkPipelineShaderStageCreateInfo(stage=v.VK_SHADER_STAGE_FRAGMENT_BIT, module=modules["frag"],
                                                    pName="main")]
        vb = [v.VkVertexInputBindingDescription(binding=n, stride=0, inputRate=v.VK_VERTEX_INPUT_RATE_VERTEX)
              for n in range(len(sh.vertex_accesses))]
        va = [v.VkVertexInputAttributeDescription(location=n, binding=n, format=v.VK_FORMAT_R32_UINT, offset=0)
              for n in range(len(sh.vertex_accesses))]
        vertex_input = v.VkPipelineVertexInputStateCreateInfo(
            vertexBindingDescriptionCount=len(vb), pVertexBindingDescriptions=vb or None,
            vertexAttributeDescriptionCount=len(va), pVertexAttributeDescriptions=va or None)
        assembly = v.VkPipelineInputAssemblyStateCreateInfo(topology=v.VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST)
        viewport = v.VkViewport(x=0, y=0, width=float(w), height=float(h), minDepth=0.0, maxDepth=1.0)
        from rgraph.vk.multi.tiles import scissor_rect

        scissor = scissor_rect(self.p, w, h)  # a sort-first tile, else all of it
        viewport_state = v.VkPipelineViewportStateCreateInfo(viewportCount=1, pViewports=[viewport], scissorCount=1,
                                                             pScissors=[scissor])
        raster = v.VkPipelineRasterizationStateCreateInfo(
            polygonMode=v.VK_POLYGON_MODE_FILL, cullMode=v.VK_CULL_MODE_NONE, frontFace=v.VK_FRONT_FACE_COUNTER_CLOCKWISE,
            lineWidth=1.0)
        multisample = v.VkPipelineMultisampleStateCreateInfo(rasterizationSamples=v.VK_SAMPLE_COUNT_1_BIT)
        depth_usage = accesses[sh.depth_access]["usage"] if sh.depth_access is not None else None
        depth_state = v.VkPipelineDepthStencilStateCreateInfo(
            depthTestEnable=v.VK_TRUE if depth_usage else v.VK_FALSE,
            depthWriteEnable=v.VK_TRUE if depth_usage == "depth_attachment" else v.VK_FALSE,
            depthCompareOp=v.VK_COMPARE_OP_ALWAYS)
        mask = (v.VK_COLOR_COMPONENT_R_BIT | v.VK_COLOR_COMPONENT_G_BIT | v.VK_COLOR_COMPONENT_B_BIT
                | v.VK_COLOR_COMPONENT_A_BIT)
        blends = []
        for i in sh.color_accesses:
            blend = accesses[i]["usage"] == "color_attachment_blend"
            blends.append(v.VkPipelineColorBlendAttachmentState(
                blendEnable=v.VK_TRUE if blend else v.VK_FALSE,
                srcColorBlendFactor=v.VK_BLEND_FACTOR_ONE, dstColorBlendFactor=v.VK_BLEND_FACTOR_ZERO,
                colorBlendOp=v.VK_BLEND_OP_ADD, srcAlphaBlendFactor=v.VK_BLEND_FACTOR_ONE,
                dstAlphaBlendFactor=v.VK_BLEND_FACTOR_ZERO, alphaBlendOp=v.VK_BLEND_OP_ADD, colorWriteMask=mask))
        color_blend = v.VkPipelineColorBlendStateCreateInfo(attachmentCount=len(blends), pAttachments=blends or None)
        info = v.VkGraphicsPipelineCreateInfo(
            stageCount=2, pStages=stages, pVertexInputState=vertex_input, pInputAssemblyState=assembly,
            pViewportState=viewport_state, pRasterizationState=raster, pMultisampleState=multisample,
            pDepthStencilState=depth_state, pColorBlendState=color_blend, layout=self.layout,
            renderPass=self.render_pass, subpass=0)
        self.pipeline = self._own("vkDestroyPipeline", v.vkCreateGraphicsPipelines(dev, None, 1, [info], None)[0])

    def _prepare_transfer(self) -> None:
        v = vk()
        self.probe = analyze(self.p, self.res_plan)
        accesses = self.p["accesses"]
        self.staging: dict[int, tuple[HostBuffer, list[Any] | None]] = {}
        for copy in self.probe.copies:
            if copy.src_access is not None:
                continue
            a = accesses[copy.dst_access]
            res = self.res_plan[a["resource"]]
            m = modulus(res)
            data = fill_bytes(res, copy.seed % m if m else None, subresources(a), self.plan_size)
            buf = self.setup.host_buffer(len(data), v.VK_BUFFER_USAGE_TRANSFER_SRC_BIT)
            buf.write(data)
            regions = image_copy_regions(res, a)[0] if res["kind"] == "image" else None
            self.staging[copy.dst_access] = (buf, regions)
        self.scratch: dict[tuple[int, int], HostBuffer] = {}
        for s in range(self.resources.sets):
            for i in self.probe.scratch_reads:
                a = accesses[i]
                res = self.res_plan[a["resource"]]
                size = (image_copy_regions(res, a)[1] if res["kind"] == "image"
                        else int(res["size_bytes"] or res["bytes"]))
                self.scratch[(s, i)] = self.setup.host_buffer(size, v.VK_BUFFER_USAGE_TRANSFER_DST_BIT)

    # ------------------------------------------------------------------ record
    def record(self, ctx: RecordContext, set_index: int) -> None:  # type: ignore[override]
        if self.p["kind"] == "transfer":
            self._record_transfer(ctx, set_index)
            return
        sh = self.shaders
        descriptor_sets = [self.sets[set_index]] if self.sets else []
        indirect = [self._resource(i, set_index) for i in sh.indirect_accesses]
        if sh.kind == "compute":
            ctx.bind_compute(self.pipeline, self.layout, descriptor_sets)
            if len(indirect) > 1:
                raise ExecutionError(f"pass {self.p['name']!r}: the probe dispatches through one indirect buffer")
            if indirect:
                ctx.dispatch_indirect(indirect[0].handle, 48)
            else:
                ctx.dispatch(-(-sh.domain[0] // 8), -(-sh.domain[1] // 8))
            return
        vertex = [self._resource(i, set_index) for i in sh.vertex_accesses]
        index = [self._resource(i, set_index) for i in sh.index_accesses]
        for layer in range(sh.layer_count):
            ctx.begin_render_pass(self.render_pass, self.framebuffers[set_index][layer], sh.domain, self.clear_values)
            ctx.bind_graphics(self.pipeline, self.layout, descriptor_sets)
            ctx.bind_vertex_buffers([r.handle for r in vertex],
                                    [4 * HEADER_WORDS if has_header(r.plan) else 0 for r in vertex])
            share = (self.p.get("params") or {}).get("rgraph.draws")  # sort-last: the one draw is device 0's
            if share is not None and int(share[0]) != 0:
                pass
            elif indirect:
                for r in indirect:
                    ctx.draw_indirect(r.handle, 0)
            else:
                ctx.draw(3)
            for r in index:  # a degenerate extra draw that fetches the index buffer (all indices equal)
                ctx.bind_index_buffer(r.handle, 4 * HEADER_WORDS if has_header(r.plan) else 0)
                if indirect:
                    ctx.draw_indexed_indirect(indirect[0].handle, 16)
                else:
                    ctx.draw_indexed(3)
            ctx.end_render_pass()

    def _record_transfer(self, ctx: RecordContext, set_index: int) -> None:
        v = vk()
        accesses = self.p["accesses"]
        for copy in self.probe.copies:
            dst_a = accesses[copy.dst_access]
            dst = self._resource(copy.dst_access, set_index)
            dst_layout = names.layout(dst_a["layout"]) if dst.is_image else None
            if copy.src_access is None:
                buf, regions = self.staging[copy.dst_access]
                if dst.is_image:
                    ctx.copy_buffer_to_image(buf.handle, dst.handle, dst_layout, regions)
                else:
                    size = int(dst.plan["size_bytes"] or dst.plan["bytes"])
                    ctx.copy_buffer(buf.handle, dst.handle, [v.VkBufferCopy(srcOffset=0, dstOffset=0, size=size)])
                continue
            src_a = accesses[copy.src_access]
            src = self._resource(copy.src_access, set_index)
            if dst.is_image:
                aspect = names.aspect_mask(dst.plan["format"])
                regions = []
                s_sub, d_sub = src_a["subresource"], dst_a["subresource"]
                for n in range(d_sub["mips"][1] - d_sub["mips"][0]):
                    w, h = mip_extent(dst.plan, d_sub["mips"][0] + n)
                    regions.append(v.VkImageCopy(
                        srcSubresource=v.VkImageSubresourceLayers(
                            aspectMask=aspect, mipLevel=s_sub["mips"][0] + n, baseArrayLayer=s_sub["layers"][0],
                            layerCount=s_sub["layers"][1] - s_sub["layers"][0]),
                        srcOffset=v.VkOffset3D(x=0, y=0, z=0),
                        dstSubresource=v.VkImageSubresourceLayers(
                            aspectMask=aspect, mipLevel=d_sub["mips"][0] + n, baseArrayLayer=d_sub["layers"][0],
                            layerCount=d_sub["layers"][1] - d_sub["layers"][0]),
                        dstOffset=v.VkOffset3D(x=0, y=0, z=0), extent=v.VkExtent3D(width=w, height=h, depth=1)))
                ctx.copy_image(src.handle, names.layout(src_a["layout"]), dst.handle, dst_layout, regions)
            else:
                size = int(dst.plan["size_bytes"] or dst.plan["bytes"])
                ctx.copy_buffer(src.handle, dst.handle, [v.VkBufferCopy(srcOffset=0, dstOffset=0, size=size)])
        for i in self.probe.scratch_reads:
            a = accesses[i]
            src = self._resource(i, set_index)
            buf = self.scratch[(set_index, i)]
            if src.is_image:
                regions = image_copy_regions(src.plan, a)[0]
                ctx.copy_image_to_buffer(src.handle, names.layout(a["layout"]), buf.handle, regions)
            else:
                ctx.copy_buffer(src.handle, buf.handle, [v.VkBufferCopy(srcOffset=0, dstOffset=0, size=buf.size)])
