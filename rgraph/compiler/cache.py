"""A cache of compiled plans, so that an unchanged graph "recompiles" in microseconds.

Engines that rebuild their render graph every frame keep it cheap by caching on a hash of
the graph's structure (Unity's render graph) or by compiling once and re-running the plan
(Daxa). ``PlanCache.plan(...)`` takes the arguments of ``compile_graph_plan``; its key is
what the plan depends on: the graph file and every file it includes and its scene (by
content: a SHA-256 of each, re-read only when a file's size or modification time changed),
the params, the output size, the policy, the schedule, the camera, the device profile (or the identity of the live
memory-requirements provider), extra outputs and the sync mode. A hit returns the same
``Plan`` object (plans are immutable); anything else compiles and replaces the entry.

The incremental path: the loaded graph and scene are kept while their files are unchanged,
so a changed param or size is only specialised again, and when the specialised graph's structure is one compiled
before (resources, passes without their params, outputs, culled passes, and the same
compile options), that plan is reused with the new values copied in (the graph's
``params`` and ``features``, each pass's ``params``): no compiler phase runs. A param that
changes a size or a feature that culls a pass changes the structure, and recompiles.
Graphs with acceleration structures (their sizes read the scene's geometry and features)
and ``--camera`` plans always recompile.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from rgraph.compiler.pipeline import (
    DEFAULT_SCHEDULE,
    DEFAULT_SIZE,
    Frontend,
    frontend,
    plan_for_frontend,
    specialized,
)
from rgraph.plan.model import Plan
from rgraph.resources import resolve_graph
from rgraph.spec.loader import GraphSource
from rgraph.spec.scene import Scene
from rgraph.spec.specialize import Spec


@dataclass
class _File:
    path: Path
    stamp: tuple[int, int]  # (size, mtime_ns)
    digest: str


@dataclass
class _Entry:
    files: list[_File]
    plan: Plan


def _files(front: Frontend) -> list[_File]:
    """The graph's files, its includes and its scene, stamped and hashed now."""
    paths = list(dict.fromkeys([*front.source.files, front.source.path,
                                *([front.scene.path] if front.scene is not None and front.scene.path else [])]))
    return [_File(Path(p), _stamp(Path(p)), _digest(Path(p))) for p in paths]


def _stamp(path: Path) -> tuple[int, int]:
    st = path.stat()
    return st.st_size, st.st_mtime_ns


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


class PlanCache:
    """Compiled plans by what they depend on (see the module docstring); ``capacity`` entries."""

    def __init__(self, capacity: int = 32) -> None:
        self.capacity = capacity
        self.hits = 0
        self.misses = 0
        self.reused = 0  # misses answered by the incremental path (no compile)
        self._entries: OrderedDict[tuple, _Entry] = OrderedDict()
        self._by_structure: OrderedDict[tuple, Plan] = OrderedDict()
        self._loaded: OrderedDict[tuple, tuple[list[_File], GraphSource, Scene | None]] = OrderedDict()

    def plan(
        self,
        graph: str | Path,
        scene_path: str | Path | None = None,
        params: Mapping[str, str] | None = None,
        size: tuple[int, int] = DEFAULT_SIZE,
        policy: str | None = None,
        memory: Any = None,
        profile: str | None = None,
        extra_outputs: Sequence[str] = (),
        sync: str = "normal",
        schedule: str = DEFAULT_SCHEDULE,
        camera: int = 0,
    ) -> Plan:
        key = (str(Path(resolve_graph(str(graph))).resolve()), None if scene_path is None else str(Path(scene_path).resolve()),
               tuple(sorted((params or {}).items())), tuple(size), policy, profile,
               None if memory is None else id(memory), tuple(extra_outputs), sync, schedule, camera)
        entry = self._entries.get(key)
        if entry is not None and self._unchanged(entry.files):
            self._entries.move_to_end(key)
            self.hits += 1
            return entry.plan
        self.misses += 1
        front = self._frontend(key[:2], graph, scene_path, params, size)
        shape = structure(front.spec) if camera == 0 else None
        shape_key = None if shape is None else (shape, key[4:])  # policy, profile, provider, outputs, modes
        known = None if shape_key is None else self._by_structure.get(shape_key)
        if known is not None:
            self.reused += 1
            plan = with_values(known, front.spec)
        else:
            plan = plan_for_frontend(front, policy, memory, profile, extra_outputs, sync, schedule, camera)
        if shape_key is not None:
            self._by_structure[shape_key] = plan
            self._by_structure.move_to_end(shape_key)
            while len(self._by_structure) > self.capacity:
                self._by_structure.popitem(last=False)
        self._entries[key] = _Entry(_files(front), plan)
        self._entries.move_to_end(key)
        while len(self._entries) > self.capacity:
            self._entries.popitem(last=False)
        return plan

    def _frontend(self, key: tuple[str, str | None], graph: str | Path, scene_path: str | Path | None,
                  params: Mapping[str, str] | None, size: tuple[int, int]) -> Frontend:
        """``frontend``, with the loaded graph and scene kept while their files are unchanged:
        a changed param or size only specializes again. ``key``: the resolved graph and scene
        paths (``plan``'s key starts with them)."""
        loaded = self._loaded.get(key)
        if loaded is None or not self._unchanged(loaded[0]):
            front = frontend(graph, scene_path, params, size)
            self._loaded[key] = (_files(front), front.source, front.scene)
            while len(self._loaded) > self.capacity:
                self._loaded.popitem(last=False)
            return front
        return specialized(loaded[1], loaded[2], params, size)

    @staticmethod
    def _unchanged(files: list[_File]) -> bool:
        for f in files:
            try:
                stamp = _stamp(f.path)
            except OSError:
                return False
            if stamp != f.stamp:
                if _digest(f.path) != f.digest:
                    return False
                f.stamp = stamp  # touched, same bytes
        return True


def structure(spec: Spec) -> tuple | None:
    """What the compiler's phases read from ``spec``, values copied into the plan left out
    (hashable); None for graphs whose compile reads more (acceleration structures)."""
    if any(r.kind == "accel" for r in spec.resources.values()):
        return None
    passes = tuple((p.name, p.order, p.kind, p.queue, p.impl, p.requires, p.side_effects, p.accesses,
                    p.requires_any) for p in spec.passes)
    return (spec.name, spec.source, tuple(spec.size), spec.scene_name, spec.scene_source, spec.memory_policy,
            tuple(spec.resources.items()), passes, tuple(spec.outputs), tuple(spec.removed))


def with_values(plan: Plan, spec: Spec) -> Plan:
    """``plan`` (compiled from a graph of the same ``structure``) with ``spec``'s params,
    features and pass params, as ``rgraph.compiler.emit`` writes them."""
    from rgraph.compiler.emit import _frozen

    by_name = {p.name: p for p in spec.passes}
    passes = tuple(p if (values := _frozen(by_name[p.name].params)) == p.params else replace(p, params=values)
                   for p in plan.passes)
    return replace(plan, params=_frozen(spec.params), features=_frozen(spec.features),
                   passes=passes)
