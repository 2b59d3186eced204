"""A cache of compiled plans, so that an unchanged graph "recompiles" in microseconds.

Engines that rebuild their render graph every frame keep it cheap by caching on a hash of
the graph's structure (Unity's render graph) or by compiling once and re-running the plan
(Daxa). ``PlanCache.plan(...)`` takes the arguments of ``compile_graph_plan``; its key is
what the plan depends on: the graph file and every file it includes and its scene (by
content: a SHA-256 of each, re-read only when a file's size or modification time changed),
the params, the output size, the policy, the schedule, the camera, the device profile (or the identity of the live
memory-requirements provider), extra outputs and the sync mode. A hit returns the same
``Plan`` object (plans are immutable); anything else compiles and replaces the entry.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rgraph.compiler.pipeline import DEFAULT_SCHEDULE, DEFAULT_SIZE, frontend, plan_for_frontend
from rgraph.plan.model import Plan
from rgraph.resources import resolve_graph


@dataclass
class _File:
    path: Path
    stamp: tuple[int, int]  # (size, mtime_ns)
    digest: str


@dataclass
class _Entry:
    files: list[_File]
    plan: Plan


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
        self._entries: OrderedDict[tuple, _Entry] = OrderedDict()

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
        if entry is not None and self._unchanged(entry):
            self._entries.move_to_end(key)
            self.hits += 1
            return entry.plan
        self.misses += 1
        front = frontend(graph, scene_path, params, size)
        plan = plan_for_frontend(front, policy, memory, profile, extra_outputs, sync, schedule, camera)
        paths = list(dict.fromkeys([*front.source.files, front.source.path,
                                    *([front.scene.path] if front.scene is not None and front.scene.path else [])]))
        self._entries[key] = _Entry([_File(Path(p), _stamp(Path(p)), _digest(Path(p))) for p in paths], plan)
        self._entries.move_to_end(key)
        while len(self._entries) > self.capacity:
            self._entries.popitem(last=False)
        return plan

    @staticmethod
    def _unchanged(entry: _Entry) -> bool:
        for f in entry.files:
            try:
                stamp = _stamp(f.path)
            except OSError:
                return False
            if stamp != f.stamp:
                if _digest(f.path) != f.digest:
                    return False
                f.stamp = stamp  # touched, same bytes
        return True
