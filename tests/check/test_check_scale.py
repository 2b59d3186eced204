"""Generated plans: a tiny reference barrier builder (one queue, per cell, conservative)
gives clean plans; dropping a necessary barrier is caught; 16,000 passes check quickly.

The builder here is deliberately simple and separate from the compiler: it is only a
source of correct plans for the checker.
"""

from __future__ import annotations

import copy
import json
import random
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from plans.check_builder import load

from rgraph.check import check_plan
from rgraph.check.vocab import READ_MASK, WRITE_MASK, access_mask, stage_mask

GENERAL = "GENERAL"
USAGES = {  # usage -> (stages, access, layout or None for buffers, write, image?)
    "sampled": (["FRAGMENT_SHADER"], ["SHADER_SAMPLED_READ"], "SHADER_READ_ONLY_OPTIMAL", False, True),
    "sampled_cs": (["COMPUTE_SHADER"], ["SHADER_SAMPLED_READ"], "SHADER_READ_ONLY_OPTIMAL", False, True),
    "storage_read": (["COMPUTE_SHADER"], ["SHADER_STORAGE_READ"], GENERAL, False, True),
    "storage_write": (["COMPUTE_SHADER"], ["SHADER_STORAGE_WRITE"], GENERAL, True, True),
    "color": (["COLOR_ATTACHMENT_OUTPUT"], ["COLOR_ATTACHMENT_WRITE"], "COLOR_ATTACHMENT_OPTIMAL", True, True),
    "transfer_dst": (["ALL_TRANSFER"], ["TRANSFER_WRITE"], "TRANSFER_DST_OPTIMAL", True, True),
    "transfer_src": (["ALL_TRANSFER"], ["TRANSFER_READ"], "TRANSFER_SRC_OPTIMAL", False, True),
    "uniform": (["FRAGMENT_SHADER", "VERTEX_SHADER"], ["UNIFORM_READ"], None, False, False),
    "buf_read": (["COMPUTE_SHADER"], ["SHADER_STORAGE_READ"], None, False, False),
    "buf_write": (["COMPUTE_SHADER"], ["SHADER_STORAGE_WRITE"], None, True, False),
    "buf_fill": (["ALL_TRANSFER"], ["TRANSFER_WRITE"], None, True, False),
    "indirect": (["DRAW_INDIRECT"], ["INDIRECT_COMMAND_READ"], None, False, False),
}


def _pairs(stages, access):
    return {(s, a) for s in stages for a in access}


class Cell:
    __slots__ = ("layout", "write", "visible", "reads", "defined")

    def __init__(self, layout):
        self.layout = layout
        self.write = None  # (stages, access) of the last write
        self.visible = set()  # (stage, access) pairs the last write is visible to
        self.reads = set()  # stages read since the last write
        self.defined = False

    def key(self):
        return (self.layout, self.write, frozenset(self.visible), frozenset(self.reads), self.defined)


def build_barriers(passes, resources):
    """Fill in ``barriers`` for single-queue passes whose ``accesses`` are given."""
    cells = {}
    for r in resources:
        for m in range(r["mips"]):
            for layer in range(r["layers"]):
                cells[r["name"], m, layer] = Cell("UNDEFINED" if r["kind"] == "image" else None)
    for p in passes:
        p["barriers"] = []
        for a in p["accesses"]:
            stages, access, layout, write = a["stages"], a["access"], a["layout"], a["write"]
            sub = a["subresource"] or {"mips": [0, 1], "layers": [0, 1]}
            runs = {}  # group contiguous layers with the same state into one barrier per mip
            for m in range(*sub["mips"]):
                start = None
                for layer in range(*sub["layers"]):
                    c = cells[a["resource"], m, layer]
                    k = c.key()
                    if start is None or k != start[1]:
                        start = (layer, k)
                        runs.setdefault((m, layer), [layer, layer + 1, c])
                    else:
                        run = [v for (mm, _), v in runs.items() if mm == m][-1]
                        run[1] = layer + 1
            for (m, _), (l0, l1, c) in sorted(runs.items()):
                b = _barrier_for(c, stages, access, layout, write)
                if b is not None:
                    b["resource"] = a["resource"]
                    b["subresource"] = {"mips": [m, m + 1], "layers": [l0, l1]} if layout else None
                    p["barriers"].append(b)
                for layer in range(l0, l1):
                    _apply(cells[a["resource"], m, layer], b, stages, access, layout, write)


def _barrier_for(c, stages, access, layout, write):
    transition = layout is not None and c.layout != layout
    need_visible = c.write is not None and not _pairs(stages, access) <= c.visible and (c.defined or not write)
    war = write and c.reads
    if not (transition or need_visible or war or (write and c.write and not c.reads)):
        return None
    src_stages = set(c.reads) | (set(c.write[0]) if c.write else set())
    src_access = list(c.write[1]) if c.write else []
    # Removing it must be reported if it changes a layout or is the only memory dependency
    # (no reads in between). A WAR-only barrier orders execution only, and execution
    # dependencies are global, so another barrier of the same or an earlier batch may cover it.
    necessary = transition or (c.write is not None and not c.reads)
    return {"necessary": necessary, "src": {"stages": sorted(src_stages), "access": sorted(src_access),
                    "layout": (c.layout if c.defined else "UNDEFINED") if layout else None, "queue": "graphics"},
            "dst": {"stages": sorted(stages), "access": sorted(access), "layout": layout, "queue": "graphics"},
            "aliases": None}


def _apply(c, b, stages, access, layout, write):
    if b is not None:
        if layout is not None and c.layout != layout:
            c.write = ((), ())  # the transition is the last write; visible to the barrier's dst
            c.reads = set()
            c.visible = _pairs(stages, access)
            if b["src"]["layout"] == "UNDEFINED":
                c.defined = False
        else:
            c.visible |= _pairs(stages, access)
        c.layout = layout
    if write:
        c.write = (tuple(stages), tuple(x for x in access if access_mask([x]) & WRITE_MASK))
        c.visible = set()
        c.reads = set()
        c.defined = True
    else:
        c.reads |= set(stages)


def random_plan(seed: int, n_passes: int, n_resources: int = 12, big_layers: int = 0):
    rng = random.Random(seed)
    resources = []
    for i in range(n_resources):
        kind = "image" if i % 3 else "buffer"
        layers = rng.choice([1, 1, 4]) if kind == "image" else 1
        mips = rng.choice([1, 1, 3]) if kind == "image" else 1
        resources.append({"name": f"r{i}", "kind": kind, "mips": mips, "layers": layers, "lifetime": "transient",
                          "first": None, "last": None, "heap": None, "offset": None, "bytes": 4096,
                          "initial": None, "final": None})
    if big_layers:
        resources.append({"name": "atlas", "kind": "image", "mips": 1, "layers": big_layers, "lifetime": "transient",
                          "first": None, "last": None, "heap": None, "offset": None, "bytes": 1 << 20,
                          "initial": None, "final": None})
    written = set()
    passes = []
    for i in range(n_passes):
        accesses = []
        for r in rng.sample(resources, k=rng.randint(1, min(3, len(resources)))):
            image = r["kind"] == "image"
            choices = [u for u, spec in USAGES.items() if spec[4] == image]
            if r["name"] not in written:
                choices = [u for u in choices if USAGES[u][3]]
            usage = rng.choice(choices)
            stages, access, layout, write, _ = USAGES[usage]
            sub = None
            if image:
                m0 = rng.randrange(r["mips"]) if rng.random() < 0.5 else 0
                l0 = rng.randrange(r["layers"]) if rng.random() < 0.5 else 0
                m1 = rng.randint(m0 + 1, r["mips"])
                l1 = rng.randint(l0 + 1, r["layers"]) if r["name"] != "atlas" or rng.random() < 0.01 else l0 + 1
                if not write:  # read only what was fully written: take the whole resource after a first write
                    m0, m1, l0, l1 = 0, r["mips"], 0, r["layers"]
                    if (r["name"], "partial") in written:
                        continue
                sub = {"mips": [m0, m1], "layers": [l0, l1]}
                if write and (m0, m1, l0, l1) != (0, r["mips"], 0, r["layers"]) and r["name"] not in written:
                    written.add((r["name"], "partial"))
            if write and r["name"] not in written:
                if sub is None or sub == {"mips": [0, r["mips"]], "layers": [0, r["layers"]]}:
                    written.add(r["name"])
                    written.discard((r["name"], "partial"))
            accesses.append({"resource": r["name"], "subresource": sub, "usage": usage, "stages": stages,
                             "access": access, "layout": layout, "write": write})
        passes.append({"name": f"p{i}", "index": i, "queue": "graphics", "accesses": accesses, "barriers": [],
                       "releases": [], "waits": [], "signals": []})
    build_barriers(passes, resources)
    used = {}
    for p in passes:
        for a in p["accesses"]:
            lo, hi = used.get(a["resource"], (p["index"], p["index"]))
            used[a["resource"]] = (min(lo, p["index"]), max(hi, p["index"]))
    resources = [r for r in resources if r["name"] in used]
    for r in resources:
        r["first"], r["last"] = used[r["name"]]
    return {"format": "rgraph-plan/1", "queues": ["graphics"], "passes": passes, "resources": resources}


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10**9), n=st.integers(2, 25))
def test_generated_plans_are_clean_and_each_necessary_barrier_matters(seed, n):
    plan = random_plan(seed, n)
    assert check_plan(plan) == []
    for i, p in enumerate(plan["passes"]):
        for k, b in enumerate(p["barriers"]):
            if not b["necessary"]:
                continue
            mutated = copy.deepcopy(plan)
            del mutated["passes"][i]["barriers"][k]
            assert check_plan(mutated), f"dropping {p['name']}.barriers[{k}] went unnoticed: {json.dumps(b)}"


def test_generator_usages_use_known_names():
    for stages, access, _, write, _ in USAGES.values():
        assert stage_mask(stages, "access")
        assert access_mask(access) & (WRITE_MASK if write else READ_MASK)


def _timed(plan):
    start = time.perf_counter()
    hazards = check_plan(plan)
    return hazards, time.perf_counter() - start


@pytest.mark.slow
def test_16000_passes_single_queue_with_a_2048_layer_array(capsys):
    plan = random_plan(7, 16000, n_resources=60, big_layers=2048)
    hazards, seconds = _timed(plan)
    assert hazards == []
    barriers = sum(len(p["barriers"]) for p in plan["passes"])
    with capsys.disabled():
        print(f"\ncheck: 16000 passes, {barriers} barriers, {len(plan['resources'])} resources: {seconds:.2f} s")


def tiled_async_compute(copies: int):
    """The two-queue fixture repeated ``copies`` times with fresh resources and semaphore values."""
    base = load("async_compute")
    passes, resources = [], []
    for k in range(copies):
        rename = {r["name"]: f"{r['name']}_{k}" for r in base["resources"]}
        block = json.loads(json.dumps(base))
        for p in block["passes"]:
            p["index"] += 3 * k
            p["name"] = f"{p['name']}_{k}"
            for item in p["accesses"] + p["barriers"] + p["releases"]:
                item["resource"] = rename[item["resource"]]
            for sem in p["waits"] + p["signals"]:
                sem["value"] += k
            passes.append(p)
        for r in block["resources"]:
            r["name"] = rename[r["name"]]
            r["first"] += 3 * k
            r["last"] += 3 * k
            resources.append(r)
    return {**base, "passes": passes, "resources": sorted(resources, key=lambda r: r["name"])}


def test_tiled_two_queue_plan_is_clean():
    assert check_plan(tiled_async_compute(20)) == []


@pytest.mark.slow
def test_16000_passes_two_queues(capsys):
    plan = tiled_async_compute(5334)
    hazards, seconds = _timed(plan)
    assert hazards == []
    with capsys.disabled():
        print(f"\ncheck: {len(plan['passes'])} passes on 2 queues, {len(plan['resources'])} resources: {seconds:.2f} s")
