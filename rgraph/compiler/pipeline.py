"""Graph file + scene + params -> plan: the front end, then the compiler's phases.

    load -> specialize -> [cull -> schedule -> size_accels -> trace -> measure -> place -> synchronize -> emit]

The bracketed phases are ``rgraph.compiler.phases.PHASES``: each a pure function of one
``Compilation`` value. The ``Spec`` is not changed after specialization (extra outputs
and the scene path make a new one). Only the memory-requirements provider may talk to
a device.
"""

from __future__ import annotations

import gc
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

from rgraph.compiler.memory import MemoryRequirementsProvider
from rgraph.compiler.phases import Compilation, run_phases
from rgraph.defaults import DEFAULT_SCHEDULE, DEFAULT_SIZE  # re-exported: the one default everywhere
from rgraph.errors import RGraphError
from rgraph.plan import Plan, to_json_dict
from rgraph.resources import resolve_graph, resolve_scene
from rgraph.spec.loader import GraphSource, load_graph
from rgraph.spec.pydantic_errors import did_you_mean
from rgraph.spec.scene import ALL_PRESENT, Scene, load_scene
from rgraph.spec.specialize import Spec, resolve_params, specialize

DEFAULT_POLICY = "aliased"
DEFAULT_PROFILE = "lavapipe"


@dataclass
class Frontend:
    """What ``validate`` needs: the loaded graph, its scene and the specialized spec."""

    source: GraphSource
    scene: Scene | None
    spec: Spec


def scene_quantities(model: Any) -> dict[str, int]:
    """``scene.*`` expression names that are not features: ``draws`` (instances of every mesh;
    1 without a scene, like ALL_PRESENT)."""
    if model is None:
        return {"draws": 1}
    return {"draws": max(1, sum(m.instances.total if m.instances else 1 for m in model.meshes))}


def load_scene_for(source: GraphSource, scene_path: str | Path | None) -> Scene | None:
    if scene_path is not None:
        return load_scene(resolve_scene(scene_path))
    if source.default_scene is not None:
        if not source.default_scene.is_file():
            assert source.default_scene_loc is not None
            raise RGraphError.at(source.default_scene_loc, f"default scene '{source.default_scene}' not found")
        return load_scene(source.default_scene)
    return None


def frontend(
    graph: str | Path,
    scene_path: str | Path | None = None,
    params: Mapping[str, str] | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
) -> Frontend:
    source = load_graph(resolve_graph(str(graph)))
    return specialized(source, load_scene_for(source, scene_path), params, size)


def specialized(source: GraphSource, scene: Scene | None, params: Mapping[str, str] | None,
                size: tuple[int, int]) -> Frontend:
    """``frontend`` once the graph and its scene are loaded (``PlanCache`` keeps those)."""
    features = scene.features if scene else ALL_PRESENT
    resolved = resolve_params(source, params or {})
    spec = specialize(source, features=features, params=resolved, size=size, scene_name=scene.name if scene else None,
                      quantities=scene_quantities(scene.model if scene else None))
    if scene is not None and scene.path is not None:
        spec = replace(spec, scene_source=str(scene.path))
    return Frontend(source, scene, spec)


@lru_cache(maxsize=1)
def _default_provider() -> MemoryRequirementsProvider:
    """The bundled default profile, read once per process (it was 4 ms of every compile)."""
    from rgraph.memory_requirements import ProfileMemoryRequirements

    return ProfileMemoryRequirements.named(DEFAULT_PROFILE)


def compilation(
    spec: Spec,
    *,
    policy: str = DEFAULT_POLICY,
    memory_provider: MemoryRequirementsProvider | None = None,
    profile_name: str | None = None,
    schedule: str = DEFAULT_SCHEDULE,
) -> Compilation:
    """The ``Compilation`` after every phase (``.plan`` is the result); ``schedule``: ``--schedule``."""
    if memory_provider is None:
        memory_provider = _default_provider()
        profile_name = profile_name or DEFAULT_PROFILE
    # The compiler allocates many small acyclic objects; the cyclic collector would rescan
    # the whole (large) heap again and again. Nothing here creates reference cycles.
    enabled = gc.isenabled()
    gc.disable()
    try:
        return run_phases(Compilation(spec, policy, memory_provider, profile_name or "device", schedule))
    finally:
        if enabled:
            gc.enable()


def compile_plan(spec: Spec, **options: Any) -> Plan:
    """Spec -> typed plan (the part benchmarked by benchmarks/compile_scaling.py); options as ``compilation``."""
    plan = compilation(spec, **options).plan
    assert plan is not None
    return plan


def compile_spec(spec: Spec, **options: Any) -> dict[str, Any]:
    """``compile_plan`` as the decoded JSON document (for code that still reads plan dicts)."""
    return to_json_dict(compile_plan(spec, **options))


def with_outputs(spec: Spec, names: Sequence[str]) -> Spec:
    """``spec`` with resources ``names`` appended to its outputs (one already there is kept once)."""
    outputs = list(spec.outputs)
    for name in names:
        if name not in spec.resources:
            raise RGraphError.in_file(
                "<command line>", f"extra output '{name}' is not a resource{did_you_mean(name, spec.resources)}"
            )
        if name not in outputs:
            outputs.append(name)
    return spec if outputs == spec.outputs else replace(spec, outputs=outputs)


def compile_graph_plan(
    graph: str | Path,
    scene_path: str | Path | None = None,
    params: Mapping[str, str] | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    policy: str | None = None,
    memory: MemoryRequirementsProvider | None = None,
    profile: str | None = None,
    extra_outputs: Sequence[str] = (),
    sync: str = "normal",
    schedule: str = DEFAULT_SCHEDULE,
    camera: int = 0,
    split: Any = None,
) -> Plan:
    """Compile a graph file (or bundled graph name) into a typed plan.

    ``extra_outputs`` names resources kept as outputs besides the graph's own (their
    writers are not culled and the runtime reads them back), e.g. an HDR intermediate.
    ``sync="naive"`` transforms the plan with ``rgraph.compiler.naive_sync`` (a full barrier
    before every pass, one queue, no semaphores), for comparison.
    ``split`` (``rgraph.compiler.multi_device.Split``) makes a multi-device plan (FORMAT.md 6).
    """
    return plan_for_frontend(frontend(graph, scene_path, params, size), policy, memory, profile, extra_outputs, sync,
                             schedule, camera, split)


def plan_for_frontend(
    front: Frontend,
    policy: str | None = None,
    memory: MemoryRequirementsProvider | None = None,
    profile: str | None = None,
    extra_outputs: Sequence[str] = (),
    sync: str = "normal",
    schedule: str = DEFAULT_SCHEDULE,
    camera: int = 0,
    split: Any = None,
) -> Plan:
    """The rest of ``compile_graph_plan`` once the graph is loaded and specialised."""
    spec = with_outputs(front.spec, extra_outputs)
    provider = memory
    profile_name = None
    if provider is None and profile is not None:
        from rgraph.memory_requirements import ProfileMemoryRequirements

        provider = ProfileMemoryRequirements.named(profile)
        profile_name = provider.name
    chosen = policy or spec.memory_policy or DEFAULT_POLICY
    if split is not None and split.devices > 1:
        from rgraph.compiler.multi_device import compile_split

        if sync != "normal":
            raise RGraphError.in_file("<command line>", "--sync naive applies to one-device plans only")
        if schedule != DEFAULT_SCHEDULE:
            raise RGraphError.in_file("<command line>", f"--schedule {schedule} applies to one-device plans only")
        plan = compile_split(spec, split, policy=chosen, memory_provider=provider, profile_name=profile_name)
    else:
        plan = apply_sync_mode(compile_plan(spec, policy=chosen, memory_provider=provider,
                                            profile_name=profile_name, schedule=schedule), sync)
    if camera:  # every device's projection of a multi-device plan keeps it
        plan = replace(plan, camera=check_camera(front.scene, camera))
    return plan


def check_camera(scene: Scene | None, camera: int) -> int:
    """``--camera N`` against the scene's presets (FORMAT.md 7); the plan records it."""
    from rgraph.scene.build import pick_camera

    if scene is None:
        raise RGraphError.in_file("<command line>", f"--camera {camera}: the graph has no scene")
    try:
        pick_camera(scene.model, camera)
    except ValueError as exc:
        raise RGraphError.in_file("<command line>", f"--camera: {exc}") from None
    return camera


def compile_graph(*args: Any, **kwargs: Any) -> dict[str, Any]:
    """``compile_graph_plan`` as the decoded JSON document (for code that still reads plan dicts)."""
    return to_json_dict(compile_graph_plan(*args, **kwargs))


SYNC_MODES = ("normal", "naive")


def apply_sync_mode(plan: Plan, sync: str) -> Plan:
    """``plan`` as is ("normal") or transformed by ``rgraph.compiler.naive_sync`` ("naive")."""
    if sync == "normal":
        return plan
    if sync == "naive":
        from rgraph.compiler.naive_sync import naive_sync

        return naive_sync(plan)
    raise RGraphError.in_file("<command line>", f"--sync expects one of {', '.join(SYNC_MODES)}, got '{sync}'")
