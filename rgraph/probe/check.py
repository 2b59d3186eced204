"""The probe's data check: read-back outputs against the CPU simulation (``simulate``).

Every subresource the simulation predicts must hold exactly its predicted value; those it
cannot predict (formats without a probe codec, passes with ``impl:``) are listed as unchecked.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgraph.probe.simulate import simulate
from rgraph.probe.values import HEADER_WORDS, codec, has_header, header_words


@dataclass
class Mismatch:
    resource: str
    sub: tuple[int, int] | None
    expected: int | None
    got: str

    def __str__(self) -> str:
        where = f" mip {self.sub[0]} layer {self.sub[1]}" if self.sub else ""
        return f"{self.resource}{where}: expected {self.expected}, got {self.got}"


def _summary(values: np.ndarray) -> str:
    uniq, counts = np.unique(values, return_counts=True)
    order = np.argsort(-counts)[:4]
    parts = [f"{int(uniq[i])} x{int(counts[i])}" for i in order]
    return ", ".join(parts) + (" ..." if len(uniq) > 4 else "")


def compare_image(resource: dict, sub: tuple[int, int], data: bytes, expected: int | None) -> Mismatch | None:
    c = codec(resource["format"])
    if c is None or expected is None:
        return None
    values = c.decode(data)
    if values.size and np.all(values == expected):
        return None
    return Mismatch(resource["name"], sub, expected, _summary(values))


def compare_buffer(resource: dict, data: bytes, expected: int | None, plan_size: tuple[int, int]) -> list[Mismatch]:
    if expected is None:
        return []
    words = np.frombuffer(data[: len(data) // 4 * 4], dtype=np.uint32).astype(np.int64)
    out = []
    if has_header(resource):
        header = np.array(header_words(plan_size), dtype=np.int64)
        if not np.array_equal(words[:HEADER_WORDS], header):
            out.append(Mismatch(resource["name"], None, None, f"indirect header {words[:HEADER_WORDS].tolist()}"))
        words = words[HEADER_WORDS:]
    if not np.all(words == expected):
        out.append(Mismatch(resource["name"], None, expected, _summary(words)))
    return out


@dataclass
class DataCheck:
    ok: bool | None  # None: nothing could be checked by the probe (implemented passes)
    mismatches: list[Mismatch] = field(default_factory=list)
    unchecked: list[str] = field(default_factory=list)


def check_outputs(plan: dict, data: dict[tuple, bytes], frames: int) -> DataCheck:
    """Compare read-back bytes ((resource, mip, layer) -> bytes, as ``read_back`` returns)
    after ``frames`` frames with the simulation. Plans with implemented passes (``impl``)
    have no probe prediction: their outputs are unchecked (each pass has its NumPy reference)."""
    if any(p.get("impl") for p in plan["passes"]):
        return DataCheck(None, [], [f"{r['name']} (written by implemented passes; see their references)"
                                    for r in plan["resources"] if r["lifetime"] == "output"])
    expected = simulate(plan, frames)
    plan_size = tuple(plan.get("size") or (64, 64))
    resources = {r["name"]: r for r in plan["resources"]}
    mismatches: list[Mismatch] = []
    unchecked: list[str] = []
    for key, raw in sorted(data.items(), key=lambda kv: (kv[0][0], kv[0][1] or 0, kv[0][2] or 0)):
        name, mip, layer = key
        res = resources[name]
        want = expected.get(key)
        if want is None or (res["kind"] == "image" and codec(res["format"]) is None):
            unchecked.append(f"{name}" + (f" mip {mip} layer {layer}" if mip is not None else ""))
            continue
        if res["kind"] == "image":
            mm = compare_image(res, (mip, layer), raw, want)
            if mm:
                mismatches.append(mm)
        else:
            mismatches += compare_buffer(res, raw, want, plan_size)
    return DataCheck(not mismatches, mismatches, unchecked)
