"""Memory requirements without a device: predicted from a device profile JSON.

A profile (``rgraph device-profile``) holds, per format, measured requirements for a grid of
extents/mips/layers/samples and, when one fits every sample, a rule:

    per mip m (texel extent halves, floor, min 1; blocks of the format's block extent):
        mip_bytes  = align(align(blocks_x * block_bytes, row_align) * align(blocks_y, rows_align) * depth_m, mip_align)
    layer_bytes = align(sum(mip_bytes), layer_align)
    size        = align(layer_bytes * layers * samples, size_align)

This module never imports ``vulkan``. ``fit_image_rule`` and ``predict_image`` are shared
with the capture code so a rule is only kept when it reproduces every measured sample.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rgraph.errors import RGraphError

Requirements = tuple[int, int, int]  # (size, alignment, memory_type_bits)

#: A measured image sample: (width, height, depth, mips, layers, samples, size, alignment, bits).
Sample = tuple[int, int, int, int, int, int, int, int, int]

PROFILES_DIR = Path(__file__).parent / "profiles"
#: Buffer usages whose rules live in a profile's ``accel`` section (they need device addresses).
ACCEL_BUFFER_USAGES = frozenset({"accel_storage", "accel_scratch", "trace_indirect"})


def align_up(value: int, alignment: int) -> int:
    return (value + alignment - 1) // alignment * alignment


def predict_image(rule: dict[str, int], block_bytes: int, block_extent: Sequence[int],
                  extent: Sequence[int], mips: int, layers: int, samples: int) -> int:
    """The image size under ``rule`` (see the module docstring)."""
    bw, bh, bd = (list(block_extent) + [1, 1, 1])[:3]
    w, h = int(extent[0]), int(extent[1])
    d = int(extent[2]) if len(extent) > 2 else 1
    layer = 0
    for m in range(int(mips)):
        mw, mh, md = max(1, w >> m), max(1, h >> m), max(1, d >> m)
        bx, by, bz = -(-mw // bw), -(-mh // bh), -(-md // bd)
        row = align_up(bx * block_bytes, rule["row_align"])
        layer += align_up(row * align_up(by, rule["rows_align"]) * bz, rule["mip_align"])
    layer = align_up(layer, rule["layer_align"])
    return align_up(layer * int(layers) * int(samples), rule["size_align"])


_POW2 = [1 << i for i in range(17)]


def fit_image_rule(samples: Sequence[Sample], block_bytes: int, block_extent: Sequence[int]) -> dict | None:
    """The simplest rule (smallest alignments, fitted stage by stage) that predicts every sample."""
    base = {"row_align": 1, "rows_align": 1, "mip_align": 1, "layer_align": 1, "size_align": 1}

    def ok(rule: dict, subset: Sequence[Sample]) -> bool:
        return all(
            predict_image(rule, block_bytes, block_extent, s[0:3], s[3], s[4], s[5]) == s[6] for s in subset
        )

    simple = [s for s in samples if s[3] == 1 and s[4] == 1 and s[5] == 1]
    mipped = [s for s in samples if s[4] == 1 and s[5] == 1]
    for row_align in _POW2[:11]:
        for rows_align in _POW2[:7]:
            for size_align in _POW2:
                rule = dict(base, row_align=row_align, rows_align=rows_align, size_align=size_align)
                if not ok(rule, simple):
                    continue
                for mip_align in _POW2:
                    r2 = dict(rule, mip_align=mip_align)
                    if not ok(r2, mipped):
                        continue
                    for layer_align in _POW2:
                        r3 = dict(r2, layer_align=layer_align)
                        if ok(r3, samples):
                            return r3
    return None


def _pow2_at_least(value: int) -> int:
    n = 1
    while n < value:
        n *= 2
    return n


#: The images a block-linear rule covers: one mip, one sample, 2D (mip chains and MSAA differ).
BLOCK_LINEAR_DOMAIN = {"mips": 1, "samples": 1, "depth": 1}


def predict_block_linear(rule: dict[str, int], block_bytes: int, block_extent: Sequence[int],
                         extent: Sequence[int], layers: int) -> int:
    """Block-linear tiling (NVIDIA): rows of ``gob_bytes`` and blocks of ``gob_rows`` rows times
    a block height in GOBs that is the smallest power of two covering the image's height, at
    most ``max_block_gobs``; layers one after another; the total aligned to ``size_align``."""
    bw, bh = (list(block_extent) + [1, 1])[:2]
    bx, by = -(-int(extent[0]) // bw), -(-int(extent[1]) // bh)
    gobs = min(rule["max_block_gobs"], _pow2_at_least(-(-by // rule["gob_rows"])))
    layer = align_up(bx * block_bytes, rule["gob_bytes"]) * align_up(by, rule["gob_rows"] * gobs)
    return align_up(layer * int(layers), rule["size_align"])


def fit_block_linear_rule(samples: Sequence[Sample], block_bytes: int, block_extent: Sequence[int]) -> dict | None:
    """A block-linear rule predicting every sample in ``BLOCK_LINEAR_DOMAIN`` (None if none
    does, or no sample lies in it)."""
    inside = [s for s in samples if s[3] == 1 and s[5] == 1 and s[2] == 1]
    if not inside:
        return None
    for gob_bytes, gob_rows, max_gobs, size_align in ((64, 8, 16, 512), (64, 8, 32, 512), (64, 8, 16, 1),
                                                      (64, 8, 32, 1)):
        rule = {"family": "block_linear", "gob_bytes": gob_bytes, "gob_rows": gob_rows,
                "max_block_gobs": max_gobs, "size_align": size_align, "domain": dict(BLOCK_LINEAR_DOMAIN)}
        if all(predict_block_linear(rule, block_bytes, block_extent, s[0:3], s[4]) == s[6] for s in inside):
            return rule
    return None


@dataclass
class ProfileMemoryRequirements:
    """The memory-requirements provider backed by a device profile (same API as the device one)."""

    profile: dict[str, Any]
    path: str = "<profile>"

    @classmethod
    def from_file(cls, path: str | Path) -> ProfileMemoryRequirements:
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise RGraphError.in_file(path, f"cannot read device profile: {exc}") from None
        if data.get("format") != "rgraph-device-profile/1":
            raise RGraphError.in_file(path, "not an rgraph device profile (format != rgraph-device-profile/1)")
        return cls(data, str(path))

    @classmethod
    def named(cls, name: str) -> ProfileMemoryRequirements:
        """A bundled profile (``rgraph/profiles/NAME.json``) or a path."""
        candidate = PROFILES_DIR / f"{name}.json"
        return cls.from_file(candidate if candidate.exists() else Path(name))

    @property
    def name(self) -> str:
        return str(self.profile.get("name", self.path))

    def _error(self, message: str) -> RGraphError:
        return RGraphError.in_file(self.path, message)

    def image(self, format_vk_name: str, extent: Sequence[int], mips: int, layers: int, samples: int,
              usage_names: Sequence[str]) -> Requirements:
        """The requirements of an image (memoized per argument tuple: a profile does not change;
        ``rgraph/compiler/_memory.pyx`` reads ``_image_memo`` by this key itself)."""
        memo = self.__dict__.setdefault("_image_memo", {})
        args = (format_vk_name, tuple(extent), mips, layers, samples, tuple(usage_names))
        found = memo.get(args)
        if found is None:
            found = memo[args] = self._image(format_vk_name, extent, mips, layers, samples, usage_names)
        return found

    def _image(self, format_vk_name: str, extent: Sequence[int], mips: int, layers: int, samples: int,
               usage_names: Sequence[str]) -> Requirements:
        key = format_vk_name.upper().removeprefix("VK_FORMAT_")
        entry = self.profile["formats"].get(key)
        if entry is None:
            raise self._error(f"device profile {self.name!r} has no optimal-tiling image format {key}")
        extra = sorted(set(usage_names) - set(entry["usages"]) - {"transfer_src", "transfer_dst"})
        if extra:
            raise self._error(f"device profile {self.name!r}: format {key} does not support usage {', '.join(extra)}")
        ext = [int(e) for e in (list(extent) + [1, 1])[:3]]
        if not entry.get("usage_independent", False):
            raise self._error(
                f"device profile {self.name!r}: requirements of {key} depend on usage; cannot predict offline"
            )
        measured = self._measured(key).get((*ext, int(mips), int(layers), int(samples)))
        if measured is not None:
            return measured
        rule = entry.get("rule")
        if rule is None:
            raise self._error(
                f"device profile {self.name!r}: no verified size rule for {key} and extent {ext} "
                f"mips {mips} layers {layers} samples {samples} was not measured"
            )
        if int(samples) > 1 and int(samples) not in entry.get("sample_counts", [1]):
            raise self._error(f"device profile {self.name!r}: {key} does not support {samples} samples")
        if rule.get("family") == "block_linear":
            if [int(mips), int(samples), ext[2]] != [rule["domain"]["mips"], rule["domain"]["samples"],
                                                     rule["domain"]["depth"]]:
                raise self._error(
                    f"device profile {self.name!r}: the size rule of {key} covers single-mip, single-sample 2D "
                    f"images only; extent {ext} mips {mips} layers {layers} samples {samples} was not measured "
                    "(compile on the device instead)")
            size = predict_block_linear(rule, entry["block_bytes"], entry["block_extent"], ext, layers)
        else:
            size = predict_image(rule, entry["block_bytes"], entry["block_extent"], ext, mips, layers, samples)
        return size, int(entry["alignment"]), int(entry["memory_type_bits"])

    def _measured(self, key: str) -> dict[tuple[int, ...], Requirements]:
        """A format's measured samples by (w, h, d, mips, layers, samples); the first wins."""
        index = self.__dict__.setdefault("_sample_index", {})
        found = index.get(key)
        if found is None:
            found = index[key] = {}
            for s in self.profile["formats"][key]["samples"]:
                found.setdefault(tuple(int(v) for v in s[0:6]), (int(s[6]), int(s[7]), int(s[8])))
        return found

    def _accel_section(self) -> dict[str, Any]:
        section = self.profile.get("accel")
        if section is None:
            raise self._error(f"device profile {self.name!r} has no acceleration-structure sizes (capture it with "
                              "`rgraph device-profile` on a device with VK_KHR_acceleration_structure)")
        return section

    def accel_sizes(self, level: str, count: int, max_vertex: int, update: bool) -> tuple[int, int, int]:
        from rgraph.accel_profile import predict

        try:
            return predict(self._accel_section(), level, count, max_vertex, update, self.name)
        except RGraphError as err:
            raise self._error(err.first.message) from None

    def accel_scratch_alignment(self) -> int:
        return int(self._accel_section()["scratch_alignment"])

    def buffer(self, size: int, usage_names: Sequence[str]) -> Requirements:
        """The requirements of a buffer (memoized per argument tuple, like ``image``; read by
        ``_memory.pyx`` too)."""
        memo = self.__dict__.setdefault("_buffer_memo", {})
        args = (size, tuple(usage_names))
        found = memo.get(args)
        if found is None:
            found = memo[args] = self._buffer(size, usage_names)
        return found

    def _buffer(self, size: int, usage_names: Sequence[str]) -> Requirements:
        accel = sorted(set(usage_names) & ACCEL_BUFFER_USAGES)
        if accel:
            rules = self._accel_section()["buffer"]
            missing = [u for u in accel if u not in rules]
            if missing:
                raise self._error(f"device profile {self.name!r}: no buffer rule for usage {', '.join(missing)}")
            picked = [rules[u] for u in accel]
            rest = [u for u in usage_names if u not in ACCEL_BUFFER_USAGES]
            size_align = max(r["size_align"] for r in picked)
            align = max(r["alignment"] for r in picked)
            if rest:
                other, other_align, _ = self.buffer(size, rest)
                return max(align_up(max(int(size), 1), size_align), other), max(align, other_align), \
                    int(picked[0]["memory_type_bits"])
            return align_up(max(int(size), 1), size_align), align, int(picked[0]["memory_type_bits"])
        rule = self.profile["buffer"]
        usage_names = sorted({"storage_rw" if u.startswith("storage_") else u for u in usage_names})
        unknown = sorted(set(usage_names) - set(rule["alignment_by_usage"]))
        if unknown:
            raise self._error(f"device profile {self.name!r}: no buffer rule for usage {', '.join(unknown)}")
        alignment = max([rule["alignment_by_usage"][u] for u in usage_names] + [rule["alignment"]])
        by_usage = rule.get("size_align_by_usage")  # older profiles: one rounding for every usage
        size_align = max(by_usage[u] for u in usage_names) if by_usage and usage_names else rule["size_align"]
        return align_up(max(int(size), 1), size_align), alignment, int(rule["memory_type_bits"])
