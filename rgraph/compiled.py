"""The compile side of the Python API: ``rgraph.load``, ``rgraph.compile`` and ``Compiled``.

    import rgraph
    spec = rgraph.load("surgery", scene="cct", size=(320, 180))   # parsed + specialized Spec
    compiled = rgraph.compile(spec)                                # or a path / bundled name
    compiled = rgraph.compile("surgery", size=(320, 180), profile="h200.json")
    with rgraph.open_device() as gpu:                              # the runtime side
        compiled = rgraph.compile("surgery", size=(320, 180), device=gpu)
    print(compiled.as_text())          # the ``rgraph inspect`` summary
    compiled.memory_analysis()         # peak, lower bound, unaliased, per heap
    compiled.save("plan.json")         # byte-identical to ``rgraph compile -o plan.json``
    compiled.plan                      # the typed plan (rgraph.plan.Plan)

Sizes and alignments come from one provider: ``device=`` (anything with a
``memory_requirements()`` method returning a provider, e.g. ``rgraph.open_device()``'s
``Gpu``), ``profile=`` (a bundled device-profile name or a JSON path), or ``memory=`` (a
provider itself, ``rgraph.compiler.memory.MemoryRequirementsProvider``); default the
bundled lavapipe profile. Bad input raises ``rgraph.errors.RGraphError``.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from rgraph.errors import RGraphError

if TYPE_CHECKING:
    from rgraph.compiler.memory import MemoryRequirementsProvider
    from rgraph.plan import Plan
    from rgraph.spec.specialize import Spec

API = "<rgraph.compile>"


class RequirementsSource(Protocol):
    """What ``device=`` accepts: an opened device that can size resources."""

    def memory_requirements(self) -> MemoryRequirementsProvider: ...


def load(path: str | Path, scene: str | Path | None = None, params: Mapping[str, Any] | None = None,
         size: tuple[int, int] | None = None) -> Spec:
    """The specialized spec of graph ``path`` (a file or bundled name) for ``scene``, ``params``, ``size``."""
    from rgraph.compiler.pipeline import DEFAULT_SIZE, frontend

    values = {k: str(v).lower() if isinstance(v, bool) else str(v) for k, v in (params or {}).items()}
    return frontend(path, scene, values, tuple(size) if size is not None else DEFAULT_SIZE).spec


def _provider(device: RequirementsSource | None, profile: str | Path | None,
              memory: MemoryRequirementsProvider | None) -> tuple[MemoryRequirementsProvider | None, str | None]:
    given = [name for name, v in (("device", device), ("profile", profile), ("memory", memory)) if v is not None]
    if len(given) > 1:
        raise RGraphError.in_file(API, f"give one of device=, profile=, memory=; got {', '.join(given)}")
    if device is not None:
        if not callable(getattr(device, "memory_requirements", None)):
            raise RGraphError.in_file(API, f"device= needs a memory_requirements() method, got {type(device).__name__}")
        return device.memory_requirements(), None
    if profile is not None:
        from rgraph.memory_requirements import ProfileMemoryRequirements

        provider = ProfileMemoryRequirements.named(str(profile))
        return provider, provider.name
    return memory, None


def compile(
    graph: Spec | str | Path,
    *,
    size: tuple[int, int] | None = None,
    scene: str | Path | None = None,
    params: Mapping[str, Any] | None = None,
    policy: str | None = None,
    profile: str | Path | None = None,
    device: RequirementsSource | None = None,
    memory: MemoryRequirementsProvider | None = None,
    extra_outputs: Sequence[str] = (),
    sync: str = "normal",
    schedule: str | None = None,
) -> Compiled:
    """Compile a spec (``rgraph.load``), a graph file or a bundled graph name.

    ``size``, ``scene`` and ``params`` apply to files and names (a spec is already
    specialized). ``policy`` defaults to the graph's ``memory_policy``, else aliased;
    ``extra_outputs``, ``sync`` and ``schedule`` are ``rgraph compile``'s extra outputs,
    ``--sync`` and ``--schedule`` (default declaration order).
    """
    from rgraph.compiler.pipeline import DEFAULT_POLICY, apply_sync_mode, compilation, with_outputs
    from rgraph.spec.specialize import Spec

    if isinstance(graph, Spec):
        given = [n for n, v in (("size", size), ("scene", scene), ("params", params)) if v is not None]
        if given:
            raise RGraphError.in_file(API, f"{', '.join(given)} only apply to a graph file, not to a loaded spec")
        spec = graph
    else:
        spec = load(graph, scene, params, size)
    spec = with_outputs(spec, extra_outputs)
    provider, profile_name = _provider(device, profile, memory)
    done = compilation(spec, policy=policy or spec.memory_policy or DEFAULT_POLICY, memory_provider=provider,
                       profile_name=profile_name, **({"schedule": schedule} if schedule else {}))
    assert done.plan is not None
    return Compiled(apply_sync_mode(done.plan, sync), spec)


@dataclass(frozen=True)
class HeapUse:
    id: int
    memory_class: str
    bytes: int
    resources: tuple[str, ...]  # placed in this heap, by offset then name


@dataclass(frozen=True)
class MemoryAnalysis:
    """Bytes of a plan: heaps allocated (``peak``), the aliasing lower bound, no aliasing at all."""

    policy: str | None
    peak_bytes: int
    lower_bound_bytes: int
    unaliased_bytes: int
    allocations: int
    heaps: tuple[HeapUse, ...]

    @property
    def ratio(self) -> float:
        """Peak over lower bound (1.0 when both are zero)."""
        return self.peak_bytes / self.lower_bound_bytes if self.lower_bound_bytes else 1.0


def memory_analysis(plan: Plan) -> MemoryAnalysis:
    placed: dict[int, list[tuple[int, str]]] = {}
    for r in plan.resources:
        if r.heap is not None:
            placed.setdefault(r.heap, []).append((r.offset or 0, r.name))
    heaps = tuple(HeapUse(h.id, h.memory_class, h.bytes, tuple(n for _, n in sorted(placed.get(h.id, ()))))
                  for h in plan.heaps)
    s = plan.stats
    return MemoryAnalysis(s.policy, s.peak_bytes or 0, s.lower_bound_bytes or 0, s.unaliased_bytes or 0,
                          s.allocations if s.allocations is not None else len(heaps), heaps)


@dataclass(frozen=True)
class Compiled:
    """A compiled plan: ``plan`` (typed), the ``spec`` it came from, and views of it."""

    plan: Plan
    spec: Spec | None = None

    def as_json(self) -> str:
        """The plan's canonical JSON text (what ``rgraph compile`` writes)."""
        from rgraph.plan import dump

        return dump(self.plan)

    def as_dict(self) -> dict[str, Any]:
        """The plan as the decoded JSON document (for code that reads plan dicts)."""
        return self.plan.to_json_dict()

    def as_text(self, width: int = 110) -> str:
        """The ``rgraph inspect`` summary: header, schedule, culled passes, stats."""
        from rgraph.report.table import make_console
        from rgraph.report.text import print_summary

        out = io.StringIO()
        print_summary(make_console(out, width=width), self.plan.to_json_dict())  # the views read plan dicts
        return out.getvalue()

    def memory_analysis(self) -> MemoryAnalysis:
        return memory_analysis(self.plan)

    def save(self, path: str | Path) -> Path:
        """Write the plan JSON to ``path``; ``RGraphError`` if it cannot be written."""
        path = Path(path)
        try:
            path.write_text(self.as_json(), encoding="utf-8")
        except OSError as exc:
            raise RGraphError.in_file(path, f"cannot write: {exc.strerror or exc}") from None
        return path
