"""CPU simulation of the probe over a plan: the value every subresource holds after N frames.

Values are integers (see ``rgraph.probe.values``) or None where the probe cannot know them
(a format without an exact encoding, undefined contents, a partial copy, an accel over the
scene's geometry: what the probe's rays hit there depends on the scene).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rgraph.probe.semantics import accel_value, analyze, raster_read_stages, subresources, trace_value
from rgraph.probe.values import UINT32, codec, initial_value, modulus

Key = tuple[str, int | None, int | None]  # (resource, mip, layer); buffers: (name, None, None)


@dataclass
class Simulation:
    plan: dict
    values: dict[Key, int | None] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.resources = {r["name"]: r for r in self.plan["resources"]}
        for r in self.resources.values():
            if r["lifetime"] in ("persistent", "imported"):
                m = modulus(r) if probe_known(r) else None
                for key in all_keys(r):
                    self.values[key] = initial_value(r["name"], m) if m else None

    def run_frame(self) -> None:
        for r in self.resources.values():
            if r["lifetime"] in ("transient", "output"):
                for key in all_keys(r):
                    self.values[key] = None
        for p in self.plan["passes"]:
            if p.get("impl"):
                raise ValueError(f"pass {p['name']!r} has impl {p['impl']!r}; the simulation covers the probe only")
            self._run_pass(p)

    def _get(self, resource: str, sub) -> int | None:
        key = (resource, *sub) if sub is not None else (resource, None, None)
        return self.values.get(key)

    def _set(self, resource: str, sub, value: int | None) -> None:
        key = (resource, *sub) if sub is not None else (resource, None, None)
        self.values[key] = value

    def _run_pass(self, p: dict) -> None:
        probe = analyze(p, self.resources)
        accesses = p["accesses"]
        if p["kind"] == "transfer":
            for copy in probe.copies:
                dst = accesses[copy.dst_access]
                dst_res = self.resources[dst["resource"]]
                dst_subs = subresources(dst)
                if copy.src_access is None:
                    m = modulus(dst_res)
                    fillable = dst_res["kind"] == "buffer" or codec(dst_res["format"]) is not None
                    for sub in dst_subs:
                        self._set(dst["resource"], sub, copy.seed % m if (m and fillable) else None)
                else:
                    src = accesses[copy.src_access]
                    src_vals = [self._get(src["resource"], s) for s in subresources(src)]
                    for sub, value in zip(dst_subs, src_vals, strict=True):
                        self._set(dst["resource"], sub, value)
            return
        total: int | None = 0
        for read in probe.reads:
            value = self._get(read.resource, read.sub)
            if value is None or total is None:
                total = None
            else:
                total = (total + value * len(read.stages)) & UINT32
        if p["kind"] != "transfer":  # the probe's rays (ray queries outside raytrace passes) per accel read
            for a in accesses:
                if a["usage"] == "accel_read":  # once per raster stage that queries, like reads
                    value = self._get(a["resource"], None)
                    times = 1 if p["kind"] != "raster" else len(raster_read_stages(a["stages"]))
                    total = None if value is None or total is None else (total + times * trace_value(value)) & UINT32
        for a in accesses:
            if a["usage"] == "accel_build":
                known = probe_known(self.resources[a["resource"]])
                self._set(a["resource"], None, accel_value(self.plan, a["resource"]) if known else None)
        for write in probe.writes:
            m = modulus(self.resources[write.resource])
            for sub in write.subs:
                if total is None or m is None:
                    self._set(write.resource, sub, None)
                    continue
                out = (write.seed + total) & UINT32
                if write.rw:
                    own = self._get(write.resource, sub)
                    if own is None:
                        self._set(write.resource, sub, None)
                        continue
                    out = (out + own) & UINT32
                self._set(write.resource, sub, out % m)


def probe_known(resource: dict) -> bool:
    """Whether the probe can predict what a resource holds: not for an accel over the scene's
    geometry (the probe's rays hit whatever the scene puts in their way)."""
    return resource["kind"] != "accel" or (resource.get("accel") or {}).get("geometry", "probe") == "probe"


def all_keys(resource: dict) -> list[Key]:
    if resource["kind"] in ("buffer", "accel"):
        return [(resource["name"], None, None)]
    return [(resource["name"], m, layer) for m in range(resource["mips"]) for layer in range(resource["layers"])]


def simulate(plan: dict, frames: int = 1) -> dict[Key, int | None]:
    """Values of every subresource after ``frames`` frames."""
    sim = Simulation(plan)
    for _ in range(frames):
        sim.run_frame()
    return sim.values
