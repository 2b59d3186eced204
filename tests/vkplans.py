"""Hand-built plans for the runtime tests (docs/plan.md), with a small barrier tracker.

Independent of the compiler on purpose: the runtime is tested against plans written from
the plan document alone. Memory sizes come from the checked-in lavapipe profile.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

from rgraph.memory_requirements import ProfileMemoryRequirements, align_up

USAGE = {  # usage -> (stages or None for the pass's shader stage, access, layout, write)
    "color_attachment": (["COLOR_ATTACHMENT_OUTPUT"], ["COLOR_ATTACHMENT_WRITE"], "COLOR_ATTACHMENT_OPTIMAL", True),
    "color_attachment_blend": (["COLOR_ATTACHMENT_OUTPUT"], ["COLOR_ATTACHMENT_READ", "COLOR_ATTACHMENT_WRITE"],
                               "COLOR_ATTACHMENT_OPTIMAL", True),
    "depth_attachment": (["EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"],
                         ["DEPTH_STENCIL_ATTACHMENT_READ", "DEPTH_STENCIL_ATTACHMENT_WRITE"],
                         "DEPTH_ATTACHMENT_OPTIMAL", True),
    "depth_read": (["EARLY_FRAGMENT_TESTS", "LATE_FRAGMENT_TESTS"], ["DEPTH_STENCIL_ATTACHMENT_READ"],
                   "DEPTH_READ_ONLY_OPTIMAL", False),
    "sampled": (None, ["SHADER_SAMPLED_READ"], "SHADER_READ_ONLY_OPTIMAL", False),
    "storage_read": (None, ["SHADER_STORAGE_READ"], "GENERAL", False),
    "storage_write": (None, ["SHADER_STORAGE_WRITE"], "GENERAL", True),
    "storage_rw": (None, ["SHADER_STORAGE_READ", "SHADER_STORAGE_WRITE"], "GENERAL", True),
    "uniform": (None, ["UNIFORM_READ"], None, False),
    "vertex": (["VERTEX_ATTRIBUTE_INPUT"], ["VERTEX_ATTRIBUTE_READ"], None, False),
    "index": (["INDEX_INPUT"], ["INDEX_READ"], None, False),
    "indirect": (["DRAW_INDIRECT"], ["INDIRECT_COMMAND_READ"], None, False),
    "transfer_src": (["COPY"], ["TRANSFER_READ"], "TRANSFER_SRC_OPTIMAL", False),
    "transfer_dst": (["COPY"], ["TRANSFER_WRITE"], "TRANSFER_DST_OPTIMAL", True),
}

_PROFILE = ProfileMemoryRequirements.named("lavapipe")


@dataclass
class _State:
    layout: str = "UNDEFINED"
    write_stages: set = field(default_factory=set)
    write_access: set = field(default_factory=set)
    read_stages: set = field(default_factory=set)
    read_access: set = field(default_factory=set)
    visible: set = field(default_factory=set)  # (stage, access) pairs the last write is visible to
    queue: str | None = None
    last_pass: int | None = None
    last_was_write: bool = False


class PlanBuilder:
    def __init__(self, size=(64, 64), name="test"):
        self.size = list(size)
        self.name = name
        self.resources: dict[str, dict] = {}
        self.passes: list[dict] = []

    def image(self, name, fmt, extent=None, *, mips=1, layers=1, lifetime="transient"):
        extent = list(extent or self.size)
        self.resources[name] = {"name": name, "kind": "image", "format": fmt, "extent": [*extent[:2], 1],
                                "mips": mips, "layers": layers, "samples": 1, "size_bytes": None,
                                "lifetime": lifetime}
        return self

    def buffer(self, name, size, *, lifetime="transient"):
        self.resources[name] = {"name": name, "kind": "buffer", "format": None, "extent": None, "mips": None,
                                "layers": None, "samples": None, "size_bytes": size, "lifetime": lifetime}
        return self

    def add_pass(self, name, kind, accesses, queue="graphics"):
        """``accesses``: (resource, usage) or (resource, usage, {stages, mips, layers})."""
        out = []
        for item in accesses:
            res, usage = item[0], item[1]
            opts = item[2] if len(item) > 2 else {}
            stages, access, layout, write = USAGE[usage]
            if stages is None:
                stages = opts.get("stages") or (["COMPUTE_SHADER"] if kind == "compute" else ["FRAGMENT_SHADER"])
            r = self.resources[res]
            if r["kind"] == "image":
                if usage == "sampled" and any(a[0] == res and a[1] == "depth_read" for a in accesses):
                    layout = "DEPTH_READ_ONLY_OPTIMAL"
                sub = {"mips": list(opts.get("mips", [0, r["mips"]])), "layers": list(opts.get("layers",
                                                                                              [0, r["layers"]]))}
            else:
                sub, layout = None, None
            out.append({"resource": res, "subresource": sub, "usage": usage, "stages": sorted(stages),
                        "access": sorted(access), "layout": layout, "write": write})
        self.passes.append({"name": name, "index": len(self.passes), "device": 0, "queue": queue, "kind": kind,
                            "impl": None, "params": {}, "accesses": out, "barriers": [], "releases": [],
                            "waits": [], "signals": []})
        return self

    # -------------------------------------------------------------- sync
    def _keys(self, access):
        r = self.resources[access["resource"]]
        if r["kind"] == "buffer":
            return [(r["name"], None, None)]
        s = access["subresource"]
        return [(r["name"], m, layer) for m in range(*s["mips"]) for layer in range(*s["layers"])]

    def _track(self, passes, states, semaphores):
        for p in passes:
            p["barriers"], p["releases"], p["waits"], p["signals"] = [], [], [], []
        for p in passes:
            for a in _merged(p["accesses"]):
                keys = self._keys(a)
                groups = [keys] if all(states[k] == states[keys[0]] for k in keys) else [[k] for k in keys]
                for group in groups:
                    self._barrier_for(passes, p, a, group, states, semaphores)

    def _barrier_for(self, passes, p, a, keys, states, semaphores):
        st = states[keys[0]]
        sub = copy.deepcopy(a["subresource"])
        if sub is not None and len(keys) == 1 and len(self._keys(a)) > 1:
            sub = {"mips": [keys[0][1], keys[0][1] + 1], "layers": [keys[0][2], keys[0][2] + 1]}
        stages, acc = set(a["stages"]), set(a["access"])
        writes = {x for x in acc if "WRITE" in x}
        layout = a["layout"]
        transition = layout is not None and layout != st.layout
        needs = transition or (a["write"] and (st.write_stages or st.read_stages)) or (
            not a["write"] and st.write_stages and not {(s, x) for s in stages for x in acc} <= st.visible)
        if st.layout == "UNDEFINED" and layout is not None:
            needs = True
        has_content = st.write_stages and (st.layout != "UNDEFINED" or layout is None)
        q_src = st.queue if (st.queue and has_content) else p["queue"]
        barrier = None
        if needs or q_src != p["queue"]:
            src_stages = st.write_stages | (st.read_stages if (a["write"] or transition) else set())
            barrier = {
                "resource": a["resource"], "subresource": sub,
                "src": {"stages": sorted(src_stages), "access": sorted(st.write_access),
                        "layout": st.layout if layout is not None else None, "queue": q_src},
                "dst": {"stages": sorted(stages), "access": sorted(acc), "layout": layout,
                        "queue": p["queue"]},
                "aliases": None,
            }
            if layout is None:
                barrier["src"]["layout"] = barrier["dst"]["layout"] = None
            p["barriers"].append(barrier)
            if q_src != p["queue"]:
                prev = passes[st.last_pass]
                prev["releases"].append(barrier)
                semaphores[prev["queue"]] = semaphores.get(prev["queue"], 0) + 1
                value = semaphores[prev["queue"]]
                prev["signals"].append({"queue": prev["queue"], "value": value, "stages": ["ALL_COMMANDS"]})
                p["waits"].append({"queue": prev["queue"], "value": value, "stages": ["ALL_COMMANDS"]})
        for k in keys:
            s = states[k]
            if a["write"]:
                s.write_stages, s.write_access = set(stages), set(writes)
                s.read_stages, s.read_access, s.visible = set(), set(), set()
            else:
                if transition:
                    s.write_stages, s.write_access, s.read_stages, s.read_access = set(stages), set(), set(), set()
                s.read_stages |= stages
                s.read_access |= acc
                s.visible |= {(x, y) for x in stages for y in acc}
            if layout is not None:
                s.layout = layout
            s.queue, s.last_pass, s.last_was_write = p["queue"], p["index"], a["write"]

    def _fresh_states(self, finals=None):
        states = {}
        for r in self.resources.values():
            keys = ([(r["name"], None, None)] if r["kind"] == "buffer" else
                    [(r["name"], m, layer) for m in range(r["mips"]) for layer in range(r["layers"])])
            for k in keys:
                if finals and r["lifetime"] in ("persistent", "imported"):
                    states[k] = copy.deepcopy(finals[k])
                else:
                    states[k] = _State()
        return states

    # -------------------------------------------------------------- build
    def build(self, alias_groups=()):
        passes = copy.deepcopy(self.passes)
        states = self._fresh_states()
        self._track(passes, states, {})
        persistent_final = states
        states = self._fresh_states(persistent_final)
        for r in self.resources.values():  # a persistent resource's frame starts in its final state
            if r["lifetime"] in ("persistent", "imported"):
                for k, s in states.items():
                    if k[0] == r["name"]:
                        s.layout = persistent_final[k].layout
        self._track(passes, states, {})
        resources = []
        for name in sorted(self.resources):
            r = dict(self.resources[name])
            used = [(p["index"], a) for p in passes for a in p["accesses"] if a["resource"] == name]
            r["usages"] = sorted({a["usage"] for _, a in used})
            r["first"] = used[0][0] if used else None
            r["last"] = used[-1][0] if used else None
            if r["kind"] == "image":
                size, alignment, bits = _PROFILE.image(r["format"], r["extent"], r["mips"], r["layers"], 1,
                                                       r["usages"])
            else:
                size, alignment, bits = _PROFILE.buffer(r["size_bytes"], r["usages"])
            r.update(bytes=size, alignment=alignment, memory_type_bits=bits,
                     memory_class="device_local_optimal" if r["kind"] == "image" else "device_local_linear")
            key = next(k for k in states if k[0] == name)
            s = states[key]
            final = ({"stages": sorted(s.read_stages), "access": sorted(s.read_access)} if s.read_stages
                     else {"stages": sorted(s.write_stages), "access": sorted(s.write_access)})
            final.update(layout=s.layout if r["kind"] == "image" else None, queue=s.queue or "graphics")
            r["final"] = final
            r["initial"] = (copy.deepcopy(final) if r["lifetime"] in ("persistent", "imported") else
                            {"stages": [], "access": [], "layout": "UNDEFINED" if r["kind"] == "image" else None,
                             "queue": final["queue"]})
            resources.append(r)
        heaps, heap_of = [], {}
        grouped = {n for g in alias_groups for n in g}
        for g in alias_groups:
            hid = len(heaps)
            members = [r for r in resources if r["name"] in g]
            heaps.append({"id": hid, "bytes": max(r["bytes"] for r in members), "memory_class": members[0]["memory_class"],
                          "alignment": max(r["alignment"] for r in members)})
            for r in members:
                heap_of[r["name"]] = (hid, 0)
        for r in resources:
            if r["name"] not in grouped:
                hid = len(heaps)
                heaps.append({"id": hid, "bytes": align_up(r["bytes"], r["alignment"]),
                              "memory_class": r["memory_class"], "alignment": r["alignment"]})
                heap_of[r["name"]] = (hid, 0)
            r["heap"], r["offset"] = heap_of[r["name"]]
        # aliasing hand-off: mark UNDEFINED first-use barriers of later occupants
        for g in alias_groups:
            order = sorted((r for r in resources if r["name"] in g), key=lambda r: r["first"])
            for prev, nxt in zip(order, order[1:], strict=False):
                for b in passes[nxt["first"]]["barriers"]:
                    if b["resource"] == nxt["name"]:
                        b["aliases"] = prev["name"]
                        last = passes[prev["last"]]
                        prev_acc = [a for a in last["accesses"] if a["resource"] == prev["name"]]
                        b["src"]["stages"] = sorted({s for a in prev_acc for s in a["stages"]} | set(b["src"]["stages"]))
                        b["src"]["access"] = sorted({x for a in prev_acc for x in a["access"] if "WRITE" in x}
                                                    | set(b["src"]["access"]))
        queues = list(dict.fromkeys(["graphics"] + [p["queue"] for p in passes]))
        return {
            "format": "rgraph-plan/1", "graph": self.name, "source": "<test>", "scene": None, "size": self.size,
            "params": {}, "device_profile": "lavapipe", "queues": queues, "passes": passes, "culled": [],
            "dropped_reads": [], "resources": resources, "heaps": heaps,
            "stats": {"barriers": sum(len(p["barriers"]) for p in passes), "policy": "dedicated"},
        }


def drop_barrier(plan, pass_name, resource):
    """A copy of ``plan`` without the barrier of ``pass_name`` on ``resource`` (a planted bug)."""
    out = copy.deepcopy(plan)
    p = next(p for p in out["passes"] if p["name"] == pass_name)
    before = len(p["barriers"])
    p["barriers"] = [b for b in p["barriers"] if b["resource"] != resource]
    assert len(p["barriers"]) < before, f"{pass_name} has no barrier on {resource}"
    return out


def _merged(accesses):
    """One synthetic access per (resource, range) of a pass: several usages share one barrier."""
    out = {}
    for a in accesses:
        key = (a["resource"], repr(a["subresource"]))
        if key not in out:
            out[key] = copy.deepcopy(a)
            continue
        m = out[key]
        m["stages"] = sorted(set(m["stages"]) | set(a["stages"]))
        m["access"] = sorted(set(m["access"]) | set(a["access"]))
        m["write"] = m["write"] or a["write"]
    return list(out.values())
