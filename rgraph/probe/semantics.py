"""What the probe does in each pass of a plan: which values it reads and what it writes.

Shared by the Vulkan recording (``rgraph.vk.probe``) and the CPU simulation; the GPU
performs the accesses for real, the simulation only does the arithmetic.

Raster and compute passes: ``S`` = sum (uint32, wrapping) of every value read through
``sampled``, ``storage_read``, ``uniform`` and ``vertex`` accesses (each (mip, layer) of an
image range counts once per shader stage it is read in: vertex and/or fragment for raster
passes). Each written subresource of the k-th write access gets ``(seed(pass, k) + S) % M``;
a ``storage_rw`` access also adds its own old value (per subresource). ``depth_read``,
``index``, ``indirect`` and the read half of ``color_attachment_blend`` are performed (depth
test, index fetch of an extra degenerate draw, indirect draw/dispatch, blending with factors
ONE/ZERO) but add nothing.

Transfer passes copy: each ``transfer_dst`` access takes the first compatible
``transfer_src`` access (image->image of one format with as many mips/layers, whose extents
cover the destination; buffer->buffer with the same header layout, at least as large);
without one it is filled from a host staging buffer with ``seed(pass, k) % M``. A source no
destination took is copied into a runtime scratch buffer, so every declared read happens.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rgraph.probe.values import modulus, seed

READ_USAGES = {"sampled", "storage_read", "uniform", "vertex"}
WRITE_USAGES = {"color_attachment", "color_attachment_blend", "depth_attachment", "storage_write", "storage_rw"}

Sub = tuple[int, int]  # (mip, layer), absolute


def subresources(access: dict) -> list[Sub | None]:
    sub = access.get("subresource")
    if sub is None:
        return [None]
    return [(m, layer) for m in range(*sub["mips"]) for layer in range(*sub["layers"])]


def mip_extent(resource: dict, mip: int) -> tuple[int, int]:
    w, h = resource["extent"][0], resource["extent"][1]
    return max(1, w >> mip), max(1, h >> mip)


@dataclass
class Read:
    access: int  # index in pass["accesses"]
    resource: str
    sub: Sub | None
    stages: tuple[str, ...]  # shader stages reading it: ("compute",) or subset of ("vertex", "fragment")


@dataclass
class Write:
    k: int  # ordinal among the pass's write accesses
    access: int
    resource: str
    subs: list[Sub | None]
    seed: int
    rw: bool


@dataclass
class Copy:
    dst_access: int
    src_access: int | None  # None: filled from host staging
    k: int
    seed: int


@dataclass
class PassProbe:
    reads: list[Read] = field(default_factory=list)
    writes: list[Write] = field(default_factory=list)
    copies: list[Copy] = field(default_factory=list)
    scratch_reads: list[int] = field(default_factory=list)  # transfer_src accesses copied to scratch


def raster_read_stages(stages: list[str]) -> tuple[str, ...]:
    out = []
    if "VERTEX_SHADER" in stages or "VERTEX_INPUT" in stages:
        out.append("vertex")
    if "FRAGMENT_SHADER" in stages or not out:
        out.append("fragment")
    return tuple(out)


def _copy_compatible(src_res: dict, src: dict, dst_res: dict, dst: dict) -> bool:
    if src_res["kind"] != dst_res["kind"]:
        return False
    if src_res["kind"] == "buffer":
        same_header = ("indirect" in src_res.get("usages", [])) == ("indirect" in dst_res.get("usages", []))
        return same_header and int(dst_res["size_bytes"] or 0) <= int(src_res["size_bytes"] or 0)
    if src_res["format"] != dst_res["format"] or src_res["samples"] != 1 or dst_res["samples"] != 1:
        return False
    s, d = src["subresource"], dst["subresource"]
    if s["mips"][1] - s["mips"][0] != d["mips"][1] - d["mips"][0]:
        return False
    if s["layers"][1] - s["layers"][0] != d["layers"][1] - d["layers"][0]:
        return False
    for i in range(d["mips"][1] - d["mips"][0]):
        sw, sh = mip_extent(src_res, s["mips"][0] + i)
        dw, dh = mip_extent(dst_res, d["mips"][0] + i)
        if dw > sw or dh > sh:
            return False
    return True


def analyze(plan_pass: dict, resources: dict[str, dict]) -> PassProbe:
    probe = PassProbe()
    # a pass of a multi-device plan keeps the seed of its one-device index (rgraph.compiler.multi_device)
    index = (plan_pass.get("params") or {}).get("rgraph.probe_index", plan_pass["index"])
    accesses = plan_pass["accesses"]
    if plan_pass["kind"] == "transfer":
        srcs = [i for i, a in enumerate(accesses) if a["usage"] == "transfer_src"]
        used: set[int] = set()
        k = 0
        for i, a in enumerate(accesses):
            if a["usage"] != "transfer_dst":
                continue
            dst_res = resources[a["resource"]]
            src = next((s for s in srcs if s not in used and
                        _copy_compatible(resources[accesses[s]["resource"]], accesses[s], dst_res, a)), None)
            if src is not None:
                used.add(src)
            probe.copies.append(Copy(i, src, k, seed(index, k)))
            k += 1
        probe.scratch_reads = [s for s in srcs if s not in used]
        return probe
    k = 0
    for i, a in enumerate(accesses):
        usage = a["usage"]
        if usage in READ_USAGES:
            stages = ("compute",) if plan_pass["kind"] == "compute" else raster_read_stages(a["stages"])
            for sub in subresources(a):
                probe.reads.append(Read(i, a["resource"], sub, stages))
        elif usage in WRITE_USAGES:
            probe.writes.append(Write(k, i, a["resource"], subresources(a), seed(index, k), usage == "storage_rw"))
            k += 1
    return probe


def modulus_of(resources: dict[str, dict], name: str) -> int | None:
    return modulus(resources[name])


# ----------------------------------------------------------------- ray tracing (FORMAT.md 5)
#: Accel values live in instance custom indices (24 bits; the probe's second instance adds 1).
ACCEL_MODULUS = 1 << 23
#: What the probe's miss shader returns.
MISS_VALUE = 90


def accel_value(plan: dict, name: str) -> int:
    """The value the probe's build of accel ``name`` stores: its first instance's custom index
    (the second one's is one more). Persistent/imported accels hold their initial value."""
    from rgraph.probe.values import initial_value

    res = next(r for r in plan["resources"] if r["name"] == name)
    if res["lifetime"] in ("persistent", "imported"):
        return initial_value(name, ACCEL_MODULUS)
    first = next(p["index"] for p in plan["passes"]
                 if any(a["resource"] == name and a["usage"] == "accel_build" for a in p["accesses"]))
    return seed(first, 64) % ACCEL_MODULUS


def trace_value(value: int) -> int:
    """What the probe's rays return for an accel holding ``value``: a ray hitting instance 0
    (value + 1), one hitting instance 1 (value + 2), one missing (MISS_VALUE)."""
    return 2 * value + 3 + MISS_VALUE
