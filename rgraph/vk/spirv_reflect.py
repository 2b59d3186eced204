"""Reflection of SPIR-V modules in pure Python: what a pipeline layout needs to know.

``reflect(spirv)`` reads the binary words (no native dependency, no ``vulkan`` import) and
reports the entry point's stage, descriptor bindings, push constant size, compute local
size, specialization constants and stage inputs/outputs. Opcode and enum numbers come from
the generated ``rgraph.vk.spirv_grammar`` tables.

Example::

    >>> r = reflect(compile_shader("blur.comp").spirv)      # doctest: +SKIP
    >>> r.local_size, [(b.set, b.binding, b.kind) for b in r.bindings]
    ((8, 8, 1), [(0, 0, 'sampled_image'), (0, 1, 'storage_image')])

Access flags (``writable``/``readable``) follow the ``NonWritable``/``NonReadable``
decorations (GLSL ``readonly``/``writeonly``), not an analysis of the code.
"""

from __future__ import annotations

import struct
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass, field

from rgraph.vk import spirv_grammar as g

_OP = g.OPCODES
_DEC = g.DECORATION
_SC = g.STORAGE_CLASS
_EM = g.EXECUTION_MODE
_DIM_NAMES = {value: name for name, value in reversed(g.DIM.items())}
_FORMAT_NAMES = {value: name for name, value in reversed(g.IMAGE_FORMAT.items())}

# execution model -> short stage name (the GLSL file extension)
_STAGE_OF_MODEL: dict[int, str] = {
    g.EXECUTION_MODEL[model]: stage
    for model, stage in (
        ("Vertex", "vert"), ("TessellationControl", "tesc"), ("TessellationEvaluation", "tese"),
        ("Geometry", "geom"), ("Fragment", "frag"), ("GLCompute", "comp"), ("Kernel", "kernel"),
        ("TaskNV", "task"), ("MeshNV", "mesh"), ("TaskEXT", "task"), ("MeshEXT", "mesh"),
        ("RayGenerationKHR", "rgen"), ("IntersectionKHR", "rint"), ("AnyHitKHR", "rahit"),
        ("ClosestHitKHR", "rchit"), ("MissKHR", "rmiss"), ("CallableKHR", "rcall"),
    )
}
# short stage name -> VkShaderStageFlagBits name
VK_STAGE_FLAGS: dict[str, str] = {
    "vert": "VK_SHADER_STAGE_VERTEX_BIT", "tesc": "VK_SHADER_STAGE_TESSELLATION_CONTROL_BIT",
    "tese": "VK_SHADER_STAGE_TESSELLATION_EVALUATION_BIT", "geom": "VK_SHADER_STAGE_GEOMETRY_BIT",
    "frag": "VK_SHADER_STAGE_FRAGMENT_BIT", "comp": "VK_SHADER_STAGE_COMPUTE_BIT",
    "task": "VK_SHADER_STAGE_TASK_BIT_EXT", "mesh": "VK_SHADER_STAGE_MESH_BIT_EXT",
    "rgen": "VK_SHADER_STAGE_RAYGEN_BIT_KHR", "rint": "VK_SHADER_STAGE_INTERSECTION_BIT_KHR",
    "rahit": "VK_SHADER_STAGE_ANY_HIT_BIT_KHR", "rchit": "VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR",
    "rmiss": "VK_SHADER_STAGE_MISS_BIT_KHR", "rcall": "VK_SHADER_STAGE_CALLABLE_BIT_KHR",
}
# Binding.kind -> VkDescriptorType name
VK_DESCRIPTOR_TYPES: dict[str, str] = {
    "sampler": "VK_DESCRIPTOR_TYPE_SAMPLER",
    "combined_image_sampler": "VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER",
    "sampled_image": "VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE",
    "storage_image": "VK_DESCRIPTOR_TYPE_STORAGE_IMAGE",
    "uniform_texel_buffer": "VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER",
    "storage_texel_buffer": "VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER",
    "uniform_buffer": "VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER",
    "storage_buffer": "VK_DESCRIPTOR_TYPE_STORAGE_BUFFER",
    "input_attachment": "VK_DESCRIPTOR_TYPE_INPUT_ATTACHMENT",
    "acceleration_structure": "VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR",
}
_COMPUTE_LIKE = frozenset({"comp", "mesh", "task", "kernel"})


class SpirvError(ValueError):
    """The bytes are not a SPIR-V module this reflector understands."""


@dataclass(frozen=True)
class EntryPoint:
    name: str
    stage: str


@dataclass(frozen=True)
class Binding:
    """One descriptor binding. ``count`` is 0 for a runtime-sized (unbounded) array."""

    set: int
    binding: int
    kind: str
    count: int
    name: str
    writable: bool
    readable: bool
    image_dim: str | None = None  # "1D" "2D" "3D" "Cube" "Buffer" "SubpassData" ... for image kinds
    image_format: str | None = None  # SPIR-V image format of storage images ("Rgba8", "Unknown")
    block_bytes: int | None = None  # declared size of a buffer block (a runtime array counts 0)
    input_attachment_index: int | None = None

    @property
    def descriptor_type(self) -> str:
        """The ``VkDescriptorType`` enumerant name, e.g. ``VK_DESCRIPTOR_TYPE_STORAGE_IMAGE``."""
        return VK_DESCRIPTOR_TYPES[self.kind]


@dataclass(frozen=True)
class SpecConstant:
    spec_id: int
    name: str
    type: str  # "bool" "int" "uint" "float" "double" "int64_t" ...
    default: bool | int | float | None  # None: an OpSpecConstantOp expression

    @property
    def size(self) -> int:
        """Bytes of the value in ``VkSpecializationMapEntry`` (bool is a 32-bit VkBool32)."""
        return 8 if self.type in ("double", "int64_t", "uint64_t") else 4 if self.type in (
            "bool", "int", "uint", "float") else 2 if "16" in self.type else 1


@dataclass(frozen=True)
class StageVariable:
    """A stage input or output (builtins excluded). ``array`` is 0 for a non-array."""

    location: int
    name: str
    type: str  # GLSL spelling: "vec4", "ivec2", "mat4", "float[3]"
    base: str  # scalar type: "float" "int" "uint" "double" "bool" "float16_t" ...
    components: int  # 1..4
    columns: int = 1  # > 1 for matrices
    array: int = 0
    component: int = 0  # the Component decoration (first component within the location)

    @property
    def vk_format(self) -> str | None:
        """The ``VkFormat`` name matching one element (vertex attribute / colour target)."""
        bits = {"float": 32, "int": 32, "uint": 32, "double": 64, "float16_t": 16, "int16_t": 16,
                "uint16_t": 16, "int64_t": 64, "uint64_t": 64}.get(self.base)
        if bits is None or self.columns != 1:
            return None
        numeric = "SFLOAT" if self.base in ("float", "double", "float16_t") else (
            "UINT" if self.base.startswith("u") else "SINT")
        channels = "".join(f"{c}{bits}" for c in "RGBA"[: self.components])
        return f"VK_FORMAT_{channels}_{numeric}"


@dataclass(frozen=True)
class Reflection:
    stage: str
    entry_point: str
    bindings: tuple[Binding, ...]
    push_constant_bytes: int
    local_size: tuple[int, int, int] | None
    spec_constants: tuple[SpecConstant, ...]
    inputs: tuple[StageVariable, ...]
    outputs: tuple[StageVariable, ...]
    entry_points: tuple[EntryPoint, ...] = ()
    local_size_spec_ids: tuple[int | None, int | None, int | None] | None = None
    spirv_version: tuple[int, int] = (1, 0)

    @property
    def vk_stage(self) -> str:
        """The ``VkShaderStageFlagBits`` name of this entry point."""
        return VK_STAGE_FLAGS[self.stage]

    def binding(self, name: str) -> Binding:
        """The binding whose variable (or anonymous block) has this name."""
        for b in self.bindings:
            if b.name == name:
                return b
        raise KeyError(f"no binding named {name!r}; have {[b.name for b in self.bindings]}")

    def sets(self) -> dict[int, tuple[Binding, ...]]:
        """Bindings grouped by descriptor set, in set order."""
        grouped: dict[int, list[Binding]] = defaultdict(list)
        for b in self.bindings:
            grouped[b.set].append(b)
        return {s: tuple(grouped[s]) for s in sorted(grouped)}


# ----------------------------------------------------------------------------- parsing


@dataclass
class _Module:
    version: tuple[int, int] = (1, 0)
    names: dict[int, str] = field(default_factory=dict)
    member_names: dict[tuple[int, int], str] = field(default_factory=dict)
    decorations: dict[int, dict[int, list[int]]] = field(default_factory=lambda: defaultdict(dict))
    member_decorations: dict[tuple[int, int], dict[int, list[int]]] = field(
        default_factory=lambda: defaultdict(dict))
    types: dict[int, tuple] = field(default_factory=dict)
    constants: dict[int, tuple[int, object, bool]] = field(default_factory=dict)  # type, value, is_spec
    variables: dict[int, tuple[int, int]] = field(default_factory=dict)  # pointer type, storage class
    entry_points: list[tuple[int, int, str, tuple[int, ...]]] = field(default_factory=list)
    modes: dict[int, list[tuple[int, tuple[int, ...], bool]]] = field(default_factory=lambda: defaultdict(list))


def _words(spirv: bytes) -> tuple[int, ...]:
    if len(spirv) < 20 or len(spirv) % 4:
        raise SpirvError(f"not a SPIR-V module: {len(spirv)} bytes (need a 5-word header, whole words)")
    for order in "<>":
        words = struct.unpack(f"{order}{len(spirv) // 4}I", spirv)
        if words[0] == g.MAGIC_NUMBER:
            return words
    raise SpirvError(f"bad SPIR-V magic number {spirv[:4].hex()}")


def _string(words: tuple[int, ...], start: int) -> tuple[str, int]:
    """Decode a nul-terminated literal string; returns it and the index of the next word."""
    raw = bytearray()
    i = start
    while i < len(words):
        chunk = struct.pack("<I", words[i])
        i += 1
        if 0 in chunk:
            raw += chunk[: chunk.index(0)]
            break
        raw += chunk
    return raw.decode("utf-8", errors="replace"), i


def _instructions(words: tuple[int, ...]) -> Iterator[tuple[int, tuple[int, ...]]]:
    i = 5
    while i < len(words):
        count, opcode = words[i] >> 16, words[i] & 0xFFFF
        if count == 0 or i + count > len(words):
            raise SpirvError(f"truncated instruction at word {i} (opcode {opcode}, {count} words)")
        yield opcode, words[i + 1 : i + count]
        i += count


def _parse(spirv: bytes) -> _Module:
    words = _words(spirv)
    m = _Module(version=((words[1] >> 16) & 0xFF, (words[1] >> 8) & 0xFF))
    type_ops = {
        _OP["OpTypeVoid"]: lambda o: ("void",),
        _OP["OpTypeBool"]: lambda o: ("bool",),
        _OP["OpTypeInt"]: lambda o: ("int", o[1], bool(o[2])),
        _OP["OpTypeFloat"]: lambda o: ("float", o[1]),
        _OP["OpTypeVector"]: lambda o: ("vector", o[1], o[2]),
        _OP["OpTypeMatrix"]: lambda o: ("matrix", o[1], o[2]),
        # image: sampled type, dim, depth, arrayed, multisampled, sampled, format
        _OP["OpTypeImage"]: lambda o: ("image", *o[1:8]),
        _OP["OpTypeSampler"]: lambda o: ("sampler",),
        _OP["OpTypeSampledImage"]: lambda o: ("sampled_image", o[1]),
        _OP["OpTypeArray"]: lambda o: ("array", o[1], o[2]),
        _OP["OpTypeRuntimeArray"]: lambda o: ("runtime_array", o[1]),
        _OP["OpTypeStruct"]: lambda o: ("struct", *o[1:]),
        _OP["OpTypePointer"]: lambda o: ("pointer", o[1], o[2]),
        _OP["OpTypeAccelerationStructureKHR"]: lambda o: ("accel",),
    }
    scalar_constants = (_OP["OpConstant"], _OP["OpSpecConstant"])
    bool_constants = {_OP["OpConstantTrue"]: (True, False), _OP["OpConstantFalse"]: (False, False),
                      _OP["OpSpecConstantTrue"]: (True, True), _OP["OpSpecConstantFalse"]: (False, True)}
    composite_constants = {_OP["OpConstantComposite"]: False, _OP["OpSpecConstantComposite"]: True}
    for op, o in _instructions(words):
        if op in type_ops:
            m.types[o[0]] = type_ops[op](o)
        elif op == _OP["OpName"]:
            m.names[o[0]] = _string(o, 1)[0]
        elif op == _OP["OpMemberName"]:
            m.member_names[(o[0], o[1])] = _string(o, 2)[0]
        elif op in (_OP["OpDecorate"], _OP["OpDecorateId"]):
            m.decorations[o[0]][o[1]] = list(o[2:])
        elif op == _OP["OpMemberDecorate"]:
            m.member_decorations[(o[0], o[1])][o[2]] = list(o[3:])
        elif op in scalar_constants:
            m.constants[o[1]] = (o[0], _decode_scalar(m.types.get(o[0], ()), o[2:]), op != _OP["OpConstant"])
        elif op in bool_constants:
            value, spec = bool_constants[op]
            m.constants[o[1]] = (o[0], value, spec)
        elif op in composite_constants:
            m.constants[o[1]] = (o[0], tuple(o[2:]), composite_constants[op])
        elif op == _OP["OpSpecConstantOp"]:
            m.constants[o[1]] = (o[0], None, True)
        elif op == _OP["OpVariable"] and o[2] != _SC["Function"]:
            m.variables[o[1]] = (o[0], o[2])
        elif op == _OP["OpEntryPoint"]:
            name, nxt = _string(o, 2)
            m.entry_points.append((o[0], o[1], name, tuple(o[nxt:])))
        elif op in (_OP["OpExecutionMode"], _OP["OpExecutionModeId"]):
            m.modes[o[0]].append((o[1], tuple(o[2:]), op == _OP["OpExecutionModeId"]))
    return m


def _decode_scalar(t: tuple, lits: tuple[int, ...]) -> int | float | None:
    if not t or not lits:
        return None
    raw = lits[0] | (lits[1] << 32 if len(lits) > 1 else 0)
    if t[0] == "float":
        width = t[1]
        fmt = {16: "<e", 32: "<f", 64: "<d"}[width]
        return struct.unpack(fmt, raw.to_bytes(8, "little")[: width // 8])[0]
    if t[0] == "int":
        width, signed = t[1], t[2]
        raw &= (1 << width) - 1
        return raw - (1 << width) if signed and raw >> (width - 1) else raw
    return None


# ----------------------------------------------------------------------------- types


def _scalar_name(m: _Module, tid: int) -> str:
    t = m.types[tid]
    if t[0] == "bool":
        return "bool"
    if t[0] == "float":
        return {16: "float16_t", 32: "float", 64: "double"}[t[1]]
    if t[0] == "int":
        if t[1] == 32:
            return "int" if t[2] else "uint"
        return f"{'' if t[2] else 'u'}int{t[1]}_t"
    return t[0]


def _vector_prefix(scalar: str) -> str:
    return {"float": "", "double": "d", "int": "i", "uint": "u", "bool": "b"}.get(
        scalar, scalar.replace("int", "i").replace("float", "f").replace("_t", "").replace("ui", "u"))


def _type_name(m: _Module, tid: int) -> str:
    t = m.types[tid]
    if t[0] == "vector":
        return f"{_vector_prefix(_scalar_name(m, t[1]))}vec{t[2]}"
    if t[0] == "matrix":
        column = m.types[t[1]]
        prefix = "d" if _scalar_name(m, column[1]) == "double" else ""
        cols, rows = t[2], column[2]
        return f"{prefix}mat{cols}" if cols == rows else f"{prefix}mat{cols}x{rows}"
    if t[0] == "array":
        return f"{_type_name(m, t[1])}[{_array_length(m, t[2])}]"
    if t[0] == "runtime_array":
        return f"{_type_name(m, t[1])}[]"
    if t[0] == "struct":
        return m.names.get(tid) or "struct"
    return _scalar_name(m, tid)


def _array_length(m: _Module, const_id: int) -> int:
    value = m.constants.get(const_id, (0, None, False))[1]
    if not isinstance(value, int):
        raise SpirvError(f"array length %{const_id} is not a known integer constant")
    return value


def _scalar_bytes(m: _Module, tid: int) -> int:
    t = m.types[tid]
    return 4 if t[0] == "bool" else t[1] // 8


def _declared_size(m: _Module, tid: int, member: tuple[int, int] | None = None) -> int:
    """Declared byte size (as spirv-cross reports it): explicit strides, no tail padding."""
    t = m.types[tid]
    kind = t[0]
    if kind in ("bool", "int", "float"):
        return _scalar_bytes(m, tid)
    if kind == "vector":
        return t[2] * _scalar_bytes(m, t[1])
    if kind == "matrix":
        column = m.types[t[1]]
        decos = m.member_decorations.get(member, {}) if member else {}
        stride = decos.get(_DEC["MatrixStride"], [None])[0]
        if stride is None:
            return t[2] * _declared_size(m, t[1])
        return (column[2] if _DEC["RowMajor"] in decos else t[2]) * stride
    if kind == "array":
        length = _array_length(m, t[2])
        stride = m.decorations.get(tid, {}).get(_DEC["ArrayStride"], [None])[0]
        return length * (stride if stride is not None else _declared_size(m, t[1], member))
    if kind == "runtime_array":
        return 0
    if kind == "struct":
        end = 0
        for index, member_type in enumerate(t[1:]):
            offset = m.member_decorations.get((tid, index), {}).get(_DEC["Offset"], [None])[0]
            if offset is None:
                offset = end  # no explicit layout (should not happen for blocks): pack
            end = max(end, offset + _declared_size(m, member_type, (tid, index)))
        return end
    raise SpirvError(f"type %{tid} ({kind}) has no size")


def _strip_arrays(m: _Module, tid: int) -> tuple[int, int]:
    """Element type id and element count (product of array lengths; 0 if runtime-sized)."""
    count = 1
    while m.types[tid][0] in ("array", "runtime_array"):
        t = m.types[tid]
        count = 0 if t[0] == "runtime_array" else count * _array_length(m, t[2])
        tid = t[1]
    return tid, count


# ----------------------------------------------------------------------------- reflection


def _all_members_have(m: _Module, struct_id: int, decoration: int) -> bool:
    n = len(m.types[struct_id]) - 1
    return n > 0 and all(decoration in m.member_decorations.get((struct_id, i), {}) for i in range(n))


def _binding(m: _Module, var_id: int, storage: int, pointee: int) -> Binding:
    decos = m.decorations.get(var_id, {})
    elem, count = _strip_arrays(m, pointee)
    t = m.types[elem]
    name = m.names.get(var_id) or m.names.get(elem, "")
    non_writable = _DEC["NonWritable"] in decos
    non_readable = _DEC["NonReadable"] in decos
    extra: dict[str, object] = {}
    if t[0] == "struct":
        struct_decos = m.decorations.get(elem, {})
        buffer_block = storage == _SC["StorageBuffer"] or _DEC["BufferBlock"] in struct_decos
        kind = "storage_buffer" if buffer_block else "uniform_buffer"
        non_writable = non_writable or _all_members_have(m, elem, _DEC["NonWritable"]) or not buffer_block
        non_readable = non_readable or _all_members_have(m, elem, _DEC["NonReadable"])
        extra["block_bytes"] = _declared_size(m, elem)
    elif t[0] in ("image", "sampled_image"):
        image = m.types[t[1]] if t[0] == "sampled_image" else t
        dim, sampled, fmt = _DIM_NAMES.get(image[2], str(image[2])), image[6], image[7]
        extra["image_dim"] = dim
        if t[0] == "sampled_image":
            kind = "combined_image_sampler"
        elif dim == "SubpassData":
            kind = "input_attachment"
            extra["input_attachment_index"] = decos.get(_DEC["InputAttachmentIndex"], [None])[0]
        elif dim == "Buffer":
            kind = "storage_texel_buffer" if sampled == 2 else "uniform_texel_buffer"
        else:
            kind = "storage_image" if sampled == 2 else "sampled_image"
        if kind in ("storage_image", "storage_texel_buffer"):
            extra["image_format"] = _FORMAT_NAMES.get(fmt, str(fmt))
        else:
            non_writable = True
    elif t[0] == "sampler":
        kind, non_writable = "sampler", True
    elif t[0] == "accel":
        kind, non_writable = "acceleration_structure", True
    else:
        raise SpirvError(f"descriptor variable {name or var_id} has unsupported type {t[0]}")
    return Binding(
        set=decos.get(_DEC["DescriptorSet"], [0])[0],
        binding=decos.get(_DEC["Binding"], [0])[0],
        kind=kind, count=count, name=name,
        writable=not non_writable, readable=not non_readable,
        **extra,  # type: ignore[arg-type]
    )


def _locations_used(m: _Module, tid: int) -> int:
    t = m.types[tid]
    if t[0] == "array":
        return _array_length(m, t[2]) * _locations_used(m, t[1])
    if t[0] == "matrix":
        return t[2] * _locations_used(m, t[1])
    if t[0] == "vector":
        return 2 if t[2] > 2 and _scalar_bytes(m, t[1]) == 8 else 1
    if t[0] == "struct":
        return sum(_locations_used(m, member) for member in t[1:])
    return 1


def _stage_variable(m: _Module, tid: int, location: int, name: str, component: int) -> StageVariable:
    elem, count = _strip_arrays(m, tid)
    t = m.types[elem]
    columns = 1
    if t[0] == "matrix":
        columns, column = t[2], m.types[t[1]]
        components, base = column[2], _scalar_name(m, column[1])
    elif t[0] == "vector":
        components, base = t[2], _scalar_name(m, t[1])
    else:
        components, base = 1, _scalar_name(m, elem)
    is_array = m.types[tid][0] in ("array", "runtime_array")
    return StageVariable(location=location, name=name, type=_type_name(m, tid), base=base,
                         components=components, columns=columns, array=count if is_array else 0,
                         component=component)


def _stage_variables(m: _Module, var_id: int, pointee: int, per_vertex: bool) -> list[StageVariable]:
    decos = m.decorations.get(var_id, {})
    if _DEC["BuiltIn"] in decos:
        return []
    tid = pointee
    if per_vertex and m.types[tid][0] == "array":  # tess/geometry per-vertex arrays: report the element
        tid = m.types[tid][1]
    name = m.names.get(var_id, "")
    t = m.types[tid]
    if t[0] != "struct":
        location = decos.get(_DEC["Location"], [None])[0]
        if location is None:
            return []
        return [_stage_variable(m, tid, location, name, decos.get(_DEC["Component"], [0])[0])]
    members = t[1:]
    if any(_DEC["BuiltIn"] in m.member_decorations.get((tid, i), {}) for i in range(len(members))):
        return []  # gl_PerVertex and friends
    block = name or m.names.get(tid, "")
    location = decos.get(_DEC["Location"], [0])[0]
    out = []
    for i, member in enumerate(members):
        mdecos = m.member_decorations.get((tid, i), {})
        location = mdecos.get(_DEC["Location"], [location])[0]
        member_name = f"{block}.{m.member_names.get((tid, i), str(i))}"
        out.append(_stage_variable(m, member, location, member_name, mdecos.get(_DEC["Component"], [0])[0]))
        location += _locations_used(m, member)
    return out


def _spec_constants(m: _Module) -> list[SpecConstant]:
    out = []
    for cid, (tid, value, is_spec) in m.constants.items():
        spec_id = m.decorations.get(cid, {}).get(_DEC["SpecId"])
        if not is_spec or spec_id is None:
            continue
        out.append(SpecConstant(spec_id=spec_id[0], name=m.names.get(cid, ""), type=_scalar_name(m, tid),
                                default=value if not isinstance(value, tuple) else None))
    return sorted(out, key=lambda s: s.spec_id)


def _local_size(m: _Module, function: int) -> tuple[tuple[int, int, int] | None, tuple | None]:
    size: list[int] | None = None
    spec_ids: list[int | None] = [None, None, None]

    def resolve(ids: tuple[int, ...]) -> list[int]:
        values = []
        for axis, cid in enumerate(ids[:3]):
            value = m.constants.get(cid, (0, None, False))[1]
            spec = m.decorations.get(cid, {}).get(_DEC["SpecId"])
            spec_ids[axis] = spec[0] if spec else None
            values.append(value if isinstance(value, int) else 0)
        return values

    for mode, operands, by_id in m.modes.get(function, []):
        if mode == _EM["LocalSize"] and not by_id:
            size = list(operands[:3])
        elif mode == _EM["LocalSizeId"]:
            size = resolve(operands)
    # a constant decorated BuiltIn WorkgroupSize overrides the execution mode (spec 2.2.6)
    workgroup_builtin = g.BUILTIN["WorkgroupSize"]
    for cid, (_tid, value, _spec) in m.constants.items():
        builtin = m.decorations.get(cid, {}).get(_DEC["BuiltIn"])
        if builtin and builtin[0] == workgroup_builtin and isinstance(value, tuple):
            size = resolve(value)
    if size is None:
        return None, None
    return (size[0], size[1], size[2]), tuple(spec_ids)


def reflect(spirv: bytes, entry_point: str | None = None) -> Reflection:
    """Reflect one entry point (the first, or the one named) of a SPIR-V module."""
    m = _parse(bytes(spirv))
    if not m.entry_points:
        raise SpirvError("SPIR-V module has no OpEntryPoint")
    points = tuple(EntryPoint(name, _STAGE_OF_MODEL.get(model, str(model))) for model, _f, name, _i in
                   m.entry_points)
    chosen = m.entry_points[0]
    if entry_point is not None:
        matching = [e for e in m.entry_points if e[2] == entry_point]
        if not matching:
            raise SpirvError(f"no entry point {entry_point!r}; have {[p.name for p in points]}")
        chosen = matching[0]
    model, function, name, interface = chosen
    stage = _STAGE_OF_MODEL.get(model, str(model))
    # Since SPIR-V 1.4 the interface lists every global variable the entry point uses.
    lists_all_globals = m.version >= (1, 4)
    interface_ids = set(interface)
    per_vertex_inputs = stage in ("tesc", "tese", "geom")
    per_vertex_outputs = stage == "tesc" or stage == "mesh"

    bindings, inputs, outputs = [], [], []
    push_constant_bytes = 0
    for var_id, (ptr_type, storage) in m.variables.items():
        pointee = m.types[ptr_type][2]
        used = var_id in interface_ids
        if storage in (_SC["Input"], _SC["Output"]):
            if used:
                target = inputs if storage == _SC["Input"] else outputs
                per_vertex = per_vertex_inputs if storage == _SC["Input"] else per_vertex_outputs
                target += _stage_variables(m, var_id, pointee, per_vertex)
            continue
        if lists_all_globals and not used:
            continue
        if storage == _SC["PushConstant"]:
            push_constant_bytes = max(push_constant_bytes, _declared_size(m, pointee))
        elif storage in (_SC["UniformConstant"], _SC["Uniform"], _SC["StorageBuffer"]):
            if _DEC["Binding"] in m.decorations.get(var_id, {}) or storage != _SC["UniformConstant"]:
                bindings.append(_binding(m, var_id, storage, pointee))

    local_size, local_spec = _local_size(m, function) if stage in _COMPUTE_LIKE else (None, None)
    return Reflection(
        stage=stage,
        entry_point=name,
        bindings=tuple(sorted(bindings, key=lambda b: (b.set, b.binding))),
        push_constant_bytes=push_constant_bytes,
        local_size=local_size,
        spec_constants=tuple(_spec_constants(m)),
        inputs=tuple(sorted(inputs, key=lambda v: (v.location, v.component))),
        outputs=tuple(sorted(outputs, key=lambda v: (v.location, v.component))),
        entry_points=points,
        local_size_spec_ids=local_spec,
        spirv_version=m.version,
    )

