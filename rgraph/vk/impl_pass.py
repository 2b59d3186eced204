"""A plan pass run by a registered implementation (``impl:``), and its render pass.

The runtime, not the implementation, owns the VkRenderPass and framebuffers of a raster
pass: attachments are the pass's colour accesses in plan order, then its depth access;
initial and final layouts equal the plan's layouts (no implicit transitions, no subpass
dependencies), so barriers stay the graph's alone. Layered attachments give one layered
framebuffer (the implementation selects layers with ``gl_Layer``), or, for a ``multiview``
implementation with the param ``views`` > 1, a multiview render pass (view mask of all views).
"""

from __future__ import annotations

from typing import Any

from rgraph import formats
from rgraph.impl import PassImpl, lookup
from rgraph.vk import names
from rgraph.vk.device import Device
from rgraph.vk.errors import ExecutionError
from rgraph.vk.loader import vk
from rgraph.vk.passkit import PassSetup
from rgraph.vk.probe_rt import probe_class
from rgraph.vk.record_context import RecordContext
from rgraph.vk.resources import ResourceSet

ATTACHMENT_USAGES = ("color_attachment", "color_attachment_blend", "depth_attachment", "depth_read")


def attachment_accesses(plan_pass: dict) -> list[dict]:
    """Colour attachment accesses in plan order, then the depth one."""
    accesses = [a for a in plan_pass["accesses"] if a["usage"] in ATTACHMENT_USAGES]
    return ([a for a in accesses if a["usage"].startswith("color")]
            + [a for a in accesses if not a["usage"].startswith("color")])


def _load_op(a: dict, impl: type[PassImpl], first_writes: set[str]) -> str:
    chosen = impl.attachment_load.get(a["resource"])
    if chosen:
        return chosen
    if a["usage"] in ("color_attachment_blend", "depth_read"):
        return "load"
    if a["usage"] == "depth_attachment" and a["resource"] not in first_writes:
        return "load"
    return "clear"


def overrides_update(p: ImplPass) -> bool:
    """Whether the pass's implementation has per-frame host work (``PassImpl.update``)."""
    return type(p.impl).update is not PassImpl.update


class ImplPass:
    """One plan pass executed by its registered implementation (the probe, ``PROBE``, for a
    pass without ``impl:``), for every frame-in-flight set."""

    def __init__(self, device: Device, plan: dict, plan_pass: dict, resources: ResourceSet, *, sets: int,
                 scene: Any, samplers: dict[str, Any], accels: Any = None) -> None:
        self.device = device
        self.p = plan_pass
        try:
            impl_class = lookup(plan_pass["impl"]) if plan_pass.get("impl") else probe_class(plan_pass, device)
        except KeyError as exc:
            raise ExecutionError(f"pass {plan_pass['name']!r}: {exc.args[0]}") from None
        self.render_pass = None
        self.framebuffers: list[Any] = []
        self.clear_values: list[Any] = []
        self.extent: tuple[int, int] | None = None
        layers = 1
        if plan_pass["kind"] == "raster" and not impl_class.owns_render_pass:
            layers = self._prepare_render_pass(plan, resources, sets, impl_class)
        self.setup = PassSetup(device, plan, plan_pass, resources, sets=sets, render_pass=self.render_pass,
                               extent=self.extent, layers=layers, scene=scene, samplers=samplers, accels=accels)
        self.impl = impl_class(self.setup)

    def _prepare_render_pass(self, plan: dict, resources: ResourceSet, sets: int, impl: type[PassImpl]) -> int:
        v = vk()
        dev = self.device.handle
        res_plan = {r["name"]: r for r in plan["resources"]}
        att = attachment_accesses(self.p)
        if not att:
            raise ExecutionError(f"raster pass {self.p['name']!r} has no attachments")
        first_writes = {b["resource"] for b in self.p["barriers"] if b["src"]["layout"] == "UNDEFINED"}
        descriptions, color_refs, depth_ref = [], [], None
        extents, layer_counts = set(), set()
        for n, a in enumerate(att):
            res = res_plan[a["resource"]]
            sub = a["subresource"]
            if sub["mips"][1] - sub["mips"][0] != 1:
                raise ExecutionError(f"pass {self.p['name']!r}: attachment {a['resource']!r} spans several mips")
            mip = sub["mips"][0]
            extents.add((max(1, res["extent"][0] >> mip), max(1, res["extent"][1] >> mip)))
            layer_counts.add(sub["layers"][1] - sub["layers"][0])
            layout = names.layout(a["layout"])
            load = _load_op(a, impl, first_writes)
            store = (v.VK_ATTACHMENT_STORE_OP_NONE if a["usage"] == "depth_read" else v.VK_ATTACHMENT_STORE_OP_STORE)
            descriptions.append(v.VkAttachmentDescription(
                format=names.format_value(res["format"]), samples=v.VK_SAMPLE_COUNT_1_BIT,
                loadOp=getattr(v, f"VK_ATTACHMENT_LOAD_OP_{load.upper()}"), storeOp=store,
                stencilLoadOp=v.VK_ATTACHMENT_LOAD_OP_DONT_CARE, stencilStoreOp=v.VK_ATTACHMENT_STORE_OP_DONT_CARE,
                initialLayout=layout, finalLayout=layout))
            ref = v.VkAttachmentReference(attachment=n, layout=layout)
            clear = impl.clear_values.get(a["resource"])
            if a["usage"].startswith("color"):
                color_refs.append(ref)
                rgba = [float(x) for x in (clear if clear is not None else (0.0, 0.0, 0.0, 0.0))]
                self.clear_values.append(v.VkClearValue(color=v.VkClearColorValue(float32=rgba)))
            else:
                depth_ref = ref
                self.clear_values.append(v.VkClearValue(depthStencil=v.VkClearDepthStencilValue(
                    depth=float(clear if clear is not None else 0.0), stencil=0)))
        if len(extents) != 1 or len(layer_counts) != 1:
            raise ExecutionError(f"pass {self.p['name']!r}: attachments differ in extent {sorted(extents)} "
                                 f"or layer count {sorted(layer_counts)}")
        self.extent = extents.pop()
        layers = layer_counts.pop()
        subpass = v.VkSubpassDescription(
            pipelineBindPoint=v.VK_PIPELINE_BIND_POINT_GRAPHICS, colorAttachmentCount=len(color_refs),
            pColorAttachments=color_refs or None, pDepthStencilAttachment=depth_ref)
        views = int(plan.get("params", {}).get("views", 1))
        if impl.multiview == "layers":  # every attachment layer is a view (whatever ``views``)
            if layers > 1 and "multiview" not in self.device.enabled_features:
                raise ExecutionError(f"pass {self.p['name']!r}: layered attachments need the Vulkan 1.1 feature "
                                     "multiview; the device lacks it")
            views = layers
        chain = {}
        if impl.multiview and views > 1:
            if layers != views:
                raise ExecutionError(f"pass {self.p['name']!r}: views={views} needs attachments of {views} layers, "
                                     f"they have {layers}")
            mask = (1 << views) - 1
            chain["pNext"] = v.VkRenderPassMultiviewCreateInfo(subpassCount=1, pViewMasks=[mask],
                                                               correlationMaskCount=1, pCorrelationMasks=[mask])
        self.render_pass = v.vkCreateRenderPass(dev, v.VkRenderPassCreateInfo(
            attachmentCount=len(descriptions), pAttachments=descriptions, subpassCount=1, pSubpasses=[subpass],
            dependencyCount=0, **chain), None)
        framebuffer_layers = 1 if chain else layers  # multiview: the view mask selects the layers
        w, h = self.extent
        for s in range(sets):
            views = []
            for a in att:
                r = resources.get(a["resource"], s)
                sub = a["subresource"]
                aspect = v.VK_IMAGE_ASPECT_DEPTH_BIT if formats.lookup(r.plan["format"]).has_depth else None
                views.append(resources.view(r, tuple(sub["mips"]), tuple(sub["layers"]), aspect, array=layers > 1))
            self.framebuffers.append(v.vkCreateFramebuffer(dev, v.VkFramebufferCreateInfo(
                renderPass=self.render_pass, attachmentCount=len(views), pAttachments=views,
                width=w, height=h, layers=framebuffer_layers), None))
        return layers

    def record(self, ctx: RecordContext, frame_set: int) -> None:
        if self.render_pass is not None:
            assert self.extent is not None
            ctx.begin_render_pass(self.render_pass, self.framebuffers[frame_set], self.extent, self.clear_values)
            self.impl.record(ctx, frame_set)
            ctx.end_render_pass()
        else:
            self.impl.record(ctx, frame_set)

    def update(self, frame: int, frame_set: int) -> None:
        self.impl.update(frame, frame_set)

    def destroy(self) -> None:
        v = vk()
        self.impl.destroy()
        self.setup.destroy()
        for fb in self.framebuffers:
            v.vkDestroyFramebuffer(self.device.handle, fb, None)
        self.framebuffers = []
        if self.render_pass is not None:
            v.vkDestroyRenderPass(self.device.handle, self.render_pass, None)
            self.render_pass = None
