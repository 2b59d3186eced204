"""Random valid graph files, for property tests, fuzzing and the compile benchmark.

``random_graph(seed, passes)`` returns the graph as plain data (dump it with
:func:`to_yaml`). Every graph is valid: reads only read cells written earlier (or
persistent ones), usages fit formats and pass kinds, and each pass uses a resource once.
Raster passes write at least one attachment; attachments are single-mip and the same size
in one pass, so every graph is also executable by the probe implementation.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Any

COLOR_FORMATS = ("r8g8b8a8_unorm", "r16g16b16a16_sfloat", "r32_sfloat")
DEPTH_FORMAT = "d32_sfloat"
SIZES = ((16, 16), (8, 8))


@dataclass
class _Res:
    name: str
    kind: str  # image | buffer
    format: str | None
    size: tuple[int, int] = (16, 16)
    layers: int = 1
    mips: int = 1
    lifetime: str = "transient"
    written: set[tuple[int, int]] = field(default_factory=set)

    @property
    def depth(self) -> bool:
        return self.format == DEPTH_FORMAT

    def all_cells(self) -> set[tuple[int, int]]:
        return {(m, layer) for m in range(self.mips) for layer in range(self.layers)}


def _make_resources(rng: random.Random, count: int) -> list[_Res]:
    out = []
    for i in range(count):
        roll = rng.random()
        lifetime = "persistent" if rng.random() < 0.1 else "transient"
        single = lifetime == "persistent" or rng.random() < 0.3  # persistent ones end the frame uniform
        if roll < 0.2:
            out.append(_Res(f"buf{i}", "buffer", None, lifetime=lifetime))
        elif roll < 0.35:
            layers = 1 if single else rng.choice((1, 2))
            out.append(_Res(f"depth{i}", "image", DEPTH_FORMAT, rng.choice(SIZES), layers, 1, lifetime))
        else:
            fmt = rng.choice(COLOR_FORMATS)
            layers, mips = (1, 1) if single else (rng.choice((1, 2, 3)), rng.choice((1, 1, 2)))
            out.append(_Res(f"img{i}", "image", fmt, rng.choice(SIZES), layers, mips, lifetime))
    return out


def _selector(rng: random.Random, res: _Res, cells: set[tuple[int, int]], whole_ok: bool = True) -> tuple[str, set]:
    """A key for ``res`` selecting a rectangle inside ``cells`` (whole resource if possible)."""
    if res.kind == "buffer":
        return res.name, {(0, 0)}
    if whole_ok and cells >= res.all_cells() and rng.random() < 0.6:
        return res.name, res.all_cells()
    mip, layer = rng.choice(sorted(cells))
    layer_end = layer + 1
    while (mip, layer_end) in cells and layer_end < res.layers and rng.random() < 0.5:
        layer_end += 1
    sel = f"layer={layer}:{layer_end}" if layer_end - layer > 1 else f"layer={layer}"
    parts = [f"mip={mip}"] if res.mips > 1 else []
    parts.append(sel)
    return f"{res.name}[{', '.join(parts)}]", {(mip, x) for x in range(layer, layer_end)}


def _layer_key(res: _Res, layer: int) -> tuple[str, set[tuple[int, int]]]:
    """Select one layer of a single-mip resource (the whole resource when it has one layer)."""
    if res.layers == 1:
        return res.name, {(0, 0)}
    return f"{res.name}[layer={layer}]", {(0, layer)}


def random_graph(seed: int, passes: int, *, queues: bool = True, resources: int | None = None) -> dict[str, Any]:
    """A valid random graph with ``passes`` passes (deterministic for a seed)."""
    rng = random.Random(seed)
    res_list = _make_resources(rng, resources or max(3, min(passes // 2 + 2, 400)))
    graph_passes: dict[str, Any] = {}
    for i in range(passes):
        kind = rng.choices(("raster", "compute", "transfer"), weights=(5, 4, 1))[0]
        queue = "graphics"
        if queues and kind == "compute" and rng.random() < 0.3:
            queue = "compute"
        if queues and kind == "transfer" and rng.random() < 0.3:
            queue = rng.choice(("compute", "transfer"))
        entry = _random_pass(rng, kind, res_list)
        if entry is None:
            continue
        entry["kind"] = kind
        if queue != "graphics":
            entry["queue"] = queue
        if rng.random() < 0.05:
            entry["side_effects"] = True
        graph_passes[f"p{i:05d}"] = entry
    written = [r for r in res_list if r.written and r.layers == 1 and r.mips == 1]
    outputs = sorted({r.name for r in rng.sample(written, k=min(len(written), max(1, len(written) // 4)))}) if written else []
    if not outputs and graph_passes:  # never cull a graph to nothing
        graph_passes[next(reversed(graph_passes))]["side_effects"] = True
    resources_out: dict[str, Any] = {}
    for r in res_list:
        if r.kind == "buffer":
            resources_out[r.name] = {"kind": "buffer", "bytes": 256}
        else:
            resources_out[r.name] = {"kind": "image", "format": r.format, "size": list(r.size), "layers": r.layers, "mips": r.mips}
        if r.lifetime != "transient":
            resources_out[r.name]["lifetime"] = r.lifetime
    return {"rgraph": 1, "name": f"random_{seed}_{passes}", "resources": resources_out, "passes": graph_passes, "outputs": outputs}


def _random_pass(rng: random.Random, kind: str, res_list: list[_Res]) -> dict[str, Any] | None:
    reads: dict[str, Any] = {}
    writes: dict[str, Any] = {}
    used: set[str] = set()
    if kind == "raster":
        size = rng.choice(SIZES)
        targets = [r for r in res_list if r.kind == "image" and r.mips == 1 and r.size == size]
        colors = [r for r in targets if not r.depth]
        depths = [r for r in targets if r.depth]
        layer = rng.choice((0, 0, 1))  # every attachment of a pass covers one layer (same count)
        colors = [r for r in colors if r.layers > layer]
        depths = [r for r in depths if r.layers > layer]
        for r in rng.sample(colors, k=min(len(colors), rng.choice((1, 1, 2)))):
            key, cells = _layer_key(r, layer)
            blend = cells <= r.written and rng.random() < 0.3
            writes[key] = "color_attachment_blend" if blend else "color_attachment"
            used.add(r.name)
            r.written |= cells
        if depths and rng.random() < 0.5:
            r = rng.choice(depths)
            key, cells = _layer_key(r, layer)
            if cells <= r.written and rng.random() < 0.4:
                reads[key] = ["depth_read", "sampled"] if rng.random() < 0.5 else "depth_read"
            else:
                writes[key] = "depth_attachment"
                r.written |= cells
            used.add(r.name)
        if not writes and not any("depth_read" in str(v) for v in reads.values()):
            return None
    readable = [r for r in res_list if r.name not in used and (r.written or r.lifetime == "persistent")]
    for r in rng.sample(readable, k=min(len(readable), rng.choice((0, 1, 1, 2, 3)))):
        cells = r.all_cells() if r.lifetime == "persistent" else r.written
        key, _ = _selector(rng, r, cells)
        if kind == "transfer":
            usage = "transfer_src"
        elif r.kind == "buffer":
            usage = rng.choice(("uniform", "storage_read", "indirect") if kind == "compute" else ("uniform", "storage_read", "vertex", "index", "indirect"))
        else:
            usage = "sampled" if r.depth or r.format == "r8g8b8a8_unorm" or rng.random() < 0.7 else "storage_read"
        if usage == "indirect" and "indirect" in reads.values():
            usage = "uniform"  # one indirect buffer per pass
        reads[key] = usage
        used.add(r.name)
    if kind != "raster" or rng.random() < 0.2:
        writable = [r for r in res_list if r.name not in used and not r.depth]
        if kind == "raster":  # storage written from fragments: within the attachments' area
            writable = [r for r in writable if r.kind == "buffer" or (r.size[0] <= size[0] and r.size[1] <= size[1])]
        for r in rng.sample(writable, k=min(len(writable), rng.choice((1, 1, 2)))):
            key, cells = _selector(rng, r, r.all_cells())
            if kind == "transfer":
                usage = "transfer_dst"
            elif kind == "raster":
                usage = "storage_write"
            else:
                usage = "storage_rw" if cells <= r.written and rng.random() < 0.3 else "storage_write"
            writes[key] = usage
            used.add(r.name)
            r.written |= cells
    if not writes and kind != "raster":
        return None
    entry: dict[str, Any] = {}
    if reads:
        entry["reads"] = reads
    if writes:
        entry["writes"] = writes
    return entry


def to_yaml(graph: dict[str, Any]) -> str:
    """Graph data as YAML text (flow style per pass keeps 16k-pass files compact)."""
    import io

    from ruamel.yaml import YAML

    yaml = YAML(typ="safe")
    yaml.default_flow_style = None
    yaml.width = 4096
    yaml.sort_base_mapping_type_on_output = False  # declaration order is program order
    buf = io.StringIO()
    yaml.dump(graph, buf)
    return buf.getvalue()
