"""Mutation testing of a plan's barriers against the oracles (DESIGN.md, oracle 4).

For each barrier of a plan three mutants are made:

- ``drop``: the barrier is removed. A queue-family ownership pair (the same barrier in the
  releasing pass's ``releases`` and the acquiring pass's ``barriers``) is one barrier: it
  gives three drop mutants, the whole pair, the acquire alone and the release alone.
- ``src-access``: ``src.access`` emptied (only when non-empty): the writes are not made
  available.
- ``dst-stages``: ``dst.stages`` narrowed: with several stages the logically earliest is
  dropped; with one, it is replaced by the earliest stage, ``DRAW_INDIRECT`` (the execution
  dependency still covers every later stage, but the memory dependency no longer reaches
  the real consumer). ``dst.access`` keeps only the accesses the remaining stages can
  perform, so the mutant stays valid Vulkan. Pair mutations change both halves.

Each mutant runs through the selected oracles: ``check`` (``rgraph.check.check_plan``),
``syncval`` (execution under Khronos validation with synchronization validation: any
message) and ``data`` (readback compared with the probe's CPU simulation). A mutant no
oracle catches is explained: a documented blind spot of the runtime oracles, or, when every
oracle is clean, a redundant barrier (a finding against the barrier generator).
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable, Iterable
from contextlib import ExitStack
from dataclasses import dataclass, field
from typing import Any

from rgraph.stages import supported_accesses

ORACLES = ("check", "syncval", "data")
KINDS = ("drop", "src-access", "dst-stages")
REDUNDANT = "redundant barrier (generator finding)"

# Logical pipeline order (earliest first) of the stages plans use; other stages sort last.
STAGE_ORDER = (
    "DRAW_INDIRECT", "INDEX_INPUT", "VERTEX_ATTRIBUTE_INPUT", "VERTEX_SHADER", "TESSELLATION_CONTROL_SHADER",
    "TESSELLATION_EVALUATION_SHADER", "GEOMETRY_SHADER", "TASK_SHADER_EXT", "MESH_SHADER_EXT",
    "EARLY_FRAGMENT_TESTS", "FRAGMENT_SHADER", "LATE_FRAGMENT_TESTS", "COLOR_ATTACHMENT_OUTPUT",
    "COMPUTE_SHADER", "RAY_TRACING_SHADER_KHR", "ACCELERATION_STRUCTURE_BUILD_KHR", "COPY", "BLIT", "RESOLVE",
    "CLEAR", "ALL_TRANSFER", "HOST",
)
BLIND_SPOTS = {
    "ownership": "queue family ownership transfer: syncval 1.3.239 does not track ownership transfers",
    "same_family_acquire": "dropped acquire of a same-family ownership pair: the ALL_COMMANDS semaphore wait "
                           "already orders the accesses and makes the writes visible",
    "same_family_release": "release of a same-family ownership pair: the runtime never executes it "
                           "(the pair runs as one barrier at the acquire point)",
    "aliasing": "aliasing hand-over: syncval 1.3.239 does not track memory aliasing",
    "buffer_beside_image": "dropped buffer barrier while an image barrier with the same scopes remains in the "
                           "same vkCmdPipelineBarrier2: syncval 1.3.239 misses it",
    "same_scope_neighbour": "barrier without a layout transition, missing or weakened while another barrier with "
                            "the same (or wider) scopes remains in the same vkCmdPipelineBarrier2: syncval 1.3.239 "
                            "misses it (observed on lavapipe; the buffer-beside-image case generalised)",
}


@dataclass(frozen=True)
class Site:
    """Where one copy of a barrier lives: ``plan["passes"][pass_index][section][position]``."""

    pass_index: int
    section: str  # "barriers" | "releases"
    position: int


@dataclass
class BarrierUnit:
    """One barrier of the plan; an ownership pair has an acquire and a release site."""

    barrier: dict
    acquire: Site | None
    release: Site | None

    @property
    def is_pair(self) -> bool:
        return self.acquire is not None and self.release is not None

    @property
    def crosses_queues(self) -> bool:
        return self.barrier["src"]["queue"] != self.barrier["dst"]["queue"]


@dataclass
class Mutant:
    name: str  # e.g. "drop forward/ao (acquire)"
    kind: str  # one of KINDS
    unit: BarrierUnit
    detail: str
    plan: dict
    dropped: tuple[Site, ...] = ()


@dataclass
class Outcome:
    mutant: Mutant
    caught_by: list[str] = field(default_factory=list)  # subset of ORACLES (plus "runtime error")
    hazards: list[str] = field(default_factory=list)  # check hazard kinds (unique, in order)
    messages: list[str] = field(default_factory=list)  # validation message ids (unique, in order)
    data_ok: bool | None = None
    error: str | None = None  # the runtime failed on the mutant
    check_error: str | None = None  # check_plan refused the plan (malformed for its reader)
    runtime_blind_spot: str | None = None  # why syncval/data would miss it, when known
    explanation: str | None = None  # for uncaught mutants
    seconds: float = 0.0

    @property
    def caught(self) -> bool:
        return bool(self.caught_by)

    def as_json(self) -> dict[str, Any]:
        m = self.mutant
        return {"mutant": m.name, "kind": m.kind, "resource": m.unit.barrier.get("resource"), "detail": m.detail,
                "caught_by": self.caught_by, "check_hazards": self.hazards, "validation_messages": self.messages,
                "data_ok": self.data_ok, "error": self.error, "check_error": self.check_error, "runtime_blind_spot": self.runtime_blind_spot,
                "explanation": self.explanation, "seconds": round(self.seconds, 3)}


# ----------------------------------------------------------------------------- units


def barrier_units(plan: dict) -> list[BarrierUnit]:
    """Every barrier of ``plan`` once; release/acquire copies of an ownership pair are paired."""
    releases: list[tuple[Site, dict]] = []
    for i, p in enumerate(plan["passes"]):
        for j, b in enumerate(p.get("releases", [])):
            releases.append((Site(i, "releases", j), b))
    matched: set[Site] = set()
    units: list[BarrierUnit] = []
    for i, p in enumerate(plan["passes"]):
        for j, b in enumerate(p["barriers"]):
            release = None
            if b["src"]["queue"] != b["dst"]["queue"]:
                release = next((s for s, r in releases if s not in matched and s.pass_index < i and r == b), None)
                if release is not None:
                    matched.add(release)
            units.append(BarrierUnit(b, Site(i, "barriers", j), release))
    units += [BarrierUnit(b, None, s) for s, b in releases if s not in matched]
    return units


def unit_label(plan: dict, unit: BarrierUnit) -> str:
    site = unit.acquire or unit.release
    where = plan["passes"][site.pass_index]["name"]
    sub = unit.barrier.get("subresource")
    rng = ""
    if sub:
        (m0, m1), (l0, l1) = sub["mips"], sub["layers"]
        rng = f"[m{m0}:{m1} l{l0}:{l1}]"
    prefix = "release after " if unit.acquire is None else ""
    return f"{prefix}{where}/{unit.barrier['resource']}{rng}"


# ----------------------------------------------------------------------------- mutations


def _stage_rank(stage: str) -> int:
    return STAGE_ORDER.index(stage) if stage in STAGE_ORDER else len(STAGE_ORDER)




def narrowed_dst(dst: dict) -> tuple[dict, str] | None:
    """``dst`` with a narrower stage scope, and a description; None when it cannot narrow."""
    stages = list(dst["stages"])
    if len(stages) > 1:
        earliest = min(stages, key=_stage_rank)
        kept = sorted(s for s in stages if s != earliest)
        note = f"dst stages drop {earliest}"
    elif stages and stages[0] != "DRAW_INDIRECT":
        kept = ["DRAW_INDIRECT"]
        note = f"dst stages {stages[0]} -> DRAW_INDIRECT"
    else:
        return None
    access = supported_accesses(dst["access"], kept)
    if access != sorted(dst["access"]):
        note += f", dst access {'+'.join(sorted(set(dst['access']) - set(access)))} removed"
    return {**dst, "stages": kept, "access": access}, note


def _sites(unit: BarrierUnit) -> list[Site]:
    return [s for s in (unit.acquire, unit.release) if s is not None]


def _without(plan: dict, sites: Iterable[Site]) -> dict:
    out = copy.deepcopy(plan)
    for site in sorted(sites, key=lambda s: (s.pass_index, s.section, -s.position)):
        del out["passes"][site.pass_index][site.section][site.position]
    return out


def _replaced(plan: dict, unit: BarrierUnit, barrier: dict) -> dict:
    out = copy.deepcopy(plan)
    for site in _sites(unit):
        out["passes"][site.pass_index][site.section][site.position] = copy.deepcopy(barrier)
    return out


def mutants(plan: dict, kinds: Iterable[str] = KINDS) -> list[Mutant]:
    """The mutants of ``plan`` of the given kinds, in plan order."""
    kinds = set(kinds)
    out: list[Mutant] = []
    for unit in barrier_units(plan):
        label = unit_label(plan, unit)
        b = unit.barrier
        if "drop" in kinds:
            if unit.is_pair:
                out.append(Mutant(f"drop {label} (pair)", "drop", unit, "release and acquire removed",
                                  _without(plan, _sites(unit)), tuple(_sites(unit))))
                out.append(Mutant(f"drop {label} (acquire)", "drop", unit, "acquire removed",
                                  _without(plan, [unit.acquire]), (unit.acquire,)))
                out.append(Mutant(f"drop {label} (release)", "drop", unit, "release removed",
                                  _without(plan, [unit.release]), (unit.release,)))
            else:
                out.append(Mutant(f"drop {label}", "drop", unit, "removed", _without(plan, _sites(unit)),
                                  tuple(_sites(unit))))
        if "src-access" in kinds and b["src"]["access"]:
            mutated = {**b, "src": {**b["src"], "access": []}}
            out.append(Mutant(f"src-access {label}", "src-access", unit,
                              f"src access {'+'.join(b['src']['access'])} -> none", _replaced(plan, unit, mutated)))
        if "dst-stages" in kinds:
            narrowed = narrowed_dst(b["dst"])
            if narrowed is not None:
                dst, note = narrowed
                out.append(Mutant(f"dst-stages {label}", "dst-stages", unit, note,
                                  _replaced(plan, unit, {**b, "dst": dst})))
    return out


# ----------------------------------------------------------------------------- blind spots


def _scopes(b: dict) -> tuple:
    return (tuple(b["src"]["stages"]), tuple(b["src"]["access"]), tuple(b["dst"]["stages"]),
            tuple(b["dst"]["access"]))


def _covers(other: dict, b: dict) -> bool:
    """Whether ``other``'s src and dst scopes include ``b``'s (same queues)."""
    return (other["src"]["queue"] == b["src"]["queue"] and other["dst"]["queue"] == b["dst"]["queue"]
            and all(set(x) >= set(y) for x, y in zip(_scopes(other), _scopes(b), strict=True)))


def runtime_blind_spot(plan: dict, mutant: Mutant, same_family: bool) -> str | None:
    """Why syncval and the data check may miss ``mutant``, when it is a documented blind spot.

    ``same_family``: every plan queue maps to one queue family on the device (lavapipe)."""
    unit, b = mutant.unit, mutant.unit.barrier
    if b.get("aliases"):
        return BLIND_SPOTS["aliasing"]
    if unit.crosses_queues:
        if same_family and mutant.kind == "drop" and mutant.dropped == (unit.release,):
            return BLIND_SPOTS["same_family_release"]
        if same_family and mutant.kind == "drop" and unit.acquire in mutant.dropped:
            return BLIND_SPOTS["same_family_acquire"]
        if not same_family:
            return BLIND_SPOTS["ownership"]
    if unit.acquire is not None and b["src"].get("layout") == b["dst"].get("layout"):
        site = unit.acquire
        rest = [o for k, o in enumerate(plan["passes"][site.pass_index][site.section]) if k != site.position]
        if any(_covers(o, b) for o in rest):
            kind = "buffer_beside_image" if b.get("subresource") is None else "same_scope_neighbour"
            if kind == "buffer_beside_image" and not any(o.get("subresource") is not None and _covers(o, b)
                                                         for o in rest):
                kind = "same_scope_neighbour"
            return BLIND_SPOTS[kind]
    return None


# ----------------------------------------------------------------------------- oracles

Runner = Callable[[dict], Any]  # plan -> RunResult (rgraph.vk.executor)


def run_oracles(mutant: Mutant, oracles: Iterable[str], runner: Runner | None) -> Outcome:
    """Apply the oracles to one mutant (``runner`` executes a plan; None skips execution)."""
    from rgraph.check import check_plan
    from rgraph.errors import RGraphError

    oracles = set(oracles)
    outcome = Outcome(mutant)
    t0 = time.perf_counter()
    if "check" in oracles:
        try:
            hazards = check_plan(mutant.plan)
        except RGraphError as exc:  # not a catch: the checker could not read the plan at all
            outcome.check_error = str(exc)
        else:
            outcome.hazards = list(dict.fromkeys(h.kind for h in hazards))
            if hazards:
                outcome.caught_by.append("check")
    if runner is not None and oracles & {"syncval", "data"}:
        try:
            result = runner(mutant.plan)
        except Exception as exc:  # a mutant may break the device: that is a catch too, with its reason
            outcome.error = f"{type(exc).__name__}: {exc}"
            outcome.caught_by.append("runtime error")
        else:
            outcome.messages = list(dict.fromkeys(m.id_name for m in result.messages))
            outcome.data_ok = result.data_ok
            if "syncval" in oracles and result.messages:
                outcome.caught_by.append("syncval")
            if "data" in oracles and result.data_ok is False:
                outcome.caught_by.append("data")
    outcome.seconds = time.perf_counter() - t0
    return outcome


def explain(plan: dict, outcome: Outcome, oracles: Iterable[str], same_family: bool) -> None:
    """Fill ``runtime_blind_spot`` and, for an uncaught mutant, ``explanation``."""
    oracles = set(oracles)
    spot = runtime_blind_spot(plan, outcome.mutant, same_family)
    runtime_missed = not {"syncval", "data", "runtime error"} & set(outcome.caught_by)
    if runtime_missed and oracles & {"syncval", "data"}:
        outcome.runtime_blind_spot = spot
    if outcome.caught:
        return
    if spot is not None:
        outcome.explanation = f"blind spot: {spot}"
    elif outcome.check_error is not None:
        outcome.explanation = f"not caught: check could not read the plan ({outcome.check_error})"
    elif oracles >= set(ORACLES):
        outcome.explanation = REDUNDANT if outcome.mutant.kind == "drop" else (
            f"{REDUNDANT}: the weakened scope is not needed ({outcome.mutant.detail})")
    else:
        outcome.explanation = f"not caught by the oracles run ({', '.join(sorted(oracles))})"


@dataclass
class Report:
    plan: dict
    oracles: list[str]
    device: str | None
    baseline: Outcome | None
    outcomes: list[Outcome]
    seconds: float

    def summary(self) -> dict[str, tuple[int, int]]:
        out: dict[str, tuple[int, int]] = {}
        for kind in KINDS:
            rows = [o for o in self.outcomes if o.mutant.kind == kind]
            out[kind] = (sum(o.caught for o in rows), len(rows))
        return out

    def uncaught(self) -> list[Outcome]:
        return [o for o in self.outcomes if not o.caught]

    def unexplained(self) -> list[Outcome]:
        """Uncaught mutants that are neither a documented blind spot nor (with every oracle) redundant."""
        return [o for o in self.uncaught() if not o.explanation or o.explanation.startswith("not caught")]

    def check_errors(self) -> list[Outcome]:
        """Outcomes (baseline included) where check_plan could not read the plan."""
        rows = ([self.baseline] if self.baseline is not None else []) + self.outcomes
        return [o for o in rows if o.check_error is not None]

    def as_json(self) -> dict[str, Any]:
        return {
            "graph": self.plan.get("graph"), "size": self.plan.get("size"), "oracles": self.oracles,
            "device": self.device, "seconds": round(self.seconds, 2),
            "baseline": None if self.baseline is None else self.baseline.as_json(),
            "summary": {k: {"caught": c, "total": t} for k, (c, t) in self.summary().items()},
            "mutants": [o.as_json() for o in self.outcomes],
        }


def mutation_report(plan: dict, *, oracles: Iterable[str] = ORACLES, kinds: Iterable[str] = KINDS,
                    frames: int = 2, device_index: int | None = None,
                    progress: Callable[[int, int, Outcome], None] | None = None, gpu: Any = None) -> Report:
    """Run every mutant of ``plan`` through ``oracles``; the unmutated plan runs first as a baseline.

    Every pass runs the probe implementation (any ``impl`` is set aside): the probe performs
    each declared access and writes values the CPU simulation predicts, which is what makes
    the data-flow oracle see a missing barrier. Every run uses one device: ``gpu``
    (``rgraph.open_device``; with validation when syncval is an oracle), else one opened here.
    """
    oracles = [o for o in ORACLES if o in set(oracles)]
    plan = probe_only(plan)
    t0 = time.perf_counter()
    runner: Runner | None = None
    device_name: str | None = None
    same_family = True
    with ExitStack() as stack:
        if {"syncval", "data"} & set(oracles):
            from rgraph.api import open_device

            check_data = "data" in oracles
            if gpu is None:
                gpu = stack.enter_context(open_device(validate="syncval" in oracles, device=device_index,
                                                      verbose=False))
            device = gpu

            def runner(p: dict) -> Any:
                return device.load(p).run_and_check(frames, check_data=check_data)

            queues = plan.get("queues") or sorted({p["queue"] for p in plan["passes"]})
            same_family = all(gpu.device.same_family(queues[0], q) for q in queues)
        base = Mutant("baseline (unmutated)", "baseline", BarrierUnit({}, None, None), "", plan)
        baseline = run_oracles(base, oracles, runner)
        if runner is not None and baseline.error is None:
            device_name = gpu.name
        outcomes = []
        todo = mutants(plan, kinds) if baseline.error is None else []  # nothing to compare against
        for n, m in enumerate(todo):
            outcome = run_oracles(m, oracles, runner)
            explain(plan, outcome, oracles, same_family)
            outcomes.append(outcome)
            if progress is not None:
                progress(n + 1, len(todo), outcome)
    return Report(plan, oracles, device_name, baseline, outcomes, time.perf_counter() - t0)


def probe_only(plan: dict) -> dict:
    """``plan`` with every pass on the probe implementation (no ``impl``)."""
    if not any(p.get("impl") for p in plan["passes"]):
        return plan
    return {**plan, "passes": [{**p, "impl": None} for p in plan["passes"]]}
