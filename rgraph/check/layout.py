"""The plan's memory layout and pass placement, checked from the plan JSON alone.

Every placed resource must sit in a heap the plan lists, at a non-negative offset that is
a multiple of its alignment (a power of two), with its bytes inside the heap; sizes must
be plausible for any device. Passes name a known
kind and a device index. Wrong types are shape errors (:class:`PlanShapeError`); wrong
values are ``memory layout`` hazards. Overlaps in time and bytes are the aliasing
analysis's job (``aliasing.py``).
"""

from __future__ import annotations

from typing import Any

from rgraph.check import hazards as hz
from rgraph.check.plan import PlanShapeError
from rgraph.errors import quote
from rgraph.jsonloc import PathPart

#: Larger than any device's memory (the largest GPUs have a few hundred GiB): 4 TiB.
MAX_BYTES = 1 << 42
MAX_DEVICES = 64
PASS_KINDS = frozenset({"raster", "compute", "raytrace", "transfer"})


def _int(obj: dict[str, Any], key: str, path: list[PathPart]) -> int | None:
    value = obj.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int):
        raise PlanShapeError([*path, key], f"expected an integer, got {quote(value)}")
    return value


def _hazard(resource: str | None, message: str) -> hz.Hazard:
    return hz.Hazard(hz.MEMORY_LAYOUT, None, None, resource, None, f"memory layout: {message}")


def check_layout(raw: dict[str, Any]) -> list[hz.Hazard]:
    """Memory-layout hazards of the (already shape-checked) plan ``raw``."""
    found: list[hz.Hazard] = []
    _check_passes(raw)
    heaps: dict[int, int] = {}
    raw_heaps = raw.get("heaps", [])
    if not isinstance(raw_heaps, list):
        raise PlanShapeError(["heaps"], f"expected a list, got {type(raw_heaps).__name__}")
    for i, heap in enumerate(raw_heaps):
        at: list[PathPart] = ["heaps", i]
        if not isinstance(heap, dict):
            raise PlanShapeError(at, f"expected an object, got {type(heap).__name__}")
        hid, size = _int(heap, "id", at), _int(heap, "bytes", at)
        if hid is None or size is None:
            raise PlanShapeError(at, "a heap needs an integer 'id' and 'bytes'")
        if hid in heaps:
            found.append(_hazard(None, f"heap {hid} is listed twice"))
        if not 0 <= size <= MAX_BYTES:
            found.append(_hazard(None, f"heap {hid} has {size:,} bytes (expected 0 .. {MAX_BYTES:,})"))
        heaps[hid] = size
    for i, res in enumerate(raw.get("resources", [])):
        found.extend(_check_resource(res, ["resources", i], heaps))
    return found


def _check_passes(raw: dict[str, Any]) -> None:
    multi = raw.get("multi_device")
    devices = multi.get("devices", 1) if isinstance(multi, dict) else raw.get("devices", 1)
    if isinstance(devices, list):
        devices = len(devices)
    if isinstance(devices, bool) or not isinstance(devices, int) or not 1 <= devices <= MAX_DEVICES:
        raise PlanShapeError(["devices"], f"expected a device count 1 .. {MAX_DEVICES}, got {quote(devices)}")
    for i, p in enumerate(raw.get("passes", [])):
        at: list[PathPart] = ["passes", i]
        kind = p.get("kind")
        if kind is not None and kind not in PASS_KINDS:
            raise PlanShapeError([*at, "kind"], f"unknown pass kind {quote(kind)} (valid: {', '.join(sorted(PASS_KINDS))})")
        device = _int(p, "device", at)
        if device is not None and not 0 <= device < devices:
            raise PlanShapeError([*at, "device"], f"device index {device} out of range: the plan has {devices} "
                                                  f"device{'s' if devices != 1 else ''}")


def _check_resource(res: dict[str, Any], at: list[PathPart], heaps: dict[int, int]) -> list[hz.Hazard]:
    name = str(res.get("name"))
    heap, offset, size = _int(res, "heap", at), _int(res, "offset", at), _int(res, "bytes", at)
    alignment = _int(res, "alignment", at)
    out: list[hz.Hazard] = []
    if size is not None and not 0 <= size <= MAX_BYTES:
        out.append(_hazard(name, f"'{name}' has {size:,} bytes (expected 0 .. {MAX_BYTES:,})"))
        size = None
    if alignment is not None and (alignment < 1 or alignment & (alignment - 1) or alignment > MAX_BYTES):
        out.append(_hazard(name, f"'{name}' has alignment {alignment:,}, not a power of two"))
        alignment = None
    if heap is None and offset is None:
        return out
    if heap is None or offset is None:
        out.append(_hazard(name, f"'{name}' has {'an offset' if heap is None else 'a heap'} but no "
                                 f"{'heap' if heap is None else 'offset'}"))
        return out
    if heap not in heaps:
        out.append(_hazard(name, f"'{name}' is placed in heap {heap}, which the plan does not list"))
        return out
    heap_bytes = heaps[heap]
    if offset < 0:
        out.append(_hazard(name, f"'{name}' has a negative offset {offset:,} in heap {heap}"))
        return out
    if alignment is not None and offset % alignment:
        out.append(_hazard(name, f"'{name}' at offset {offset:,} in heap {heap} is not aligned to {alignment:,}"))
    if size is not None and offset + size > heap_bytes:
        out.append(_hazard(name, f"'{name}' bytes [{offset:,}, {offset + size:,}) lie past the end of heap {heap} "
                                 f"({heap_bytes:,} bytes)"))
    return out
