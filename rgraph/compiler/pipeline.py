"""Graph file + scene + params -> plan: the compiler's stages in order.

    load -> specialize -> cull -> schedule -> lifetimes/placement -> sync -> plan

Each stage is a pure function of the previous one's value; only the memory-requirements
provider may talk to a device.
"""

from __future__ import annotations

import gc
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rgraph.compiler import memory
from rgraph.compiler.accel import size_accels
from rgraph.compiler.memory import MemoryRequirementsProvider
from rgraph.compiler.sync import synchronize
from rgraph.defaults import DEFAULT_SIZE  # re-exported: the one default everywhere
from rgraph.errors import RGraphError
from rgraph.ir.cull import cull
from rgraph.ir.schedule import DEFAULT_SCHEDULE, schedule_passes
from rgraph.plan import build_plan
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
    scene = load_scene_for(source, scene_path)
    features = scene.features if scene else ALL_PRESENT
    resolved = resolve_params(source, params or {})
    spec = specialize(source, features=features, params=resolved, size=size, scene_name=scene.name if scene else None)
    spec.scene_source = str(scene.path) if scene is not None and scene.path is not None else None
    return Frontend(source, scene, spec)


def compile_spec(
    spec: Spec,
    *,
    policy: str = DEFAULT_POLICY,
    memory_provider: MemoryRequirementsProvider | None = None,
    profile_name: str | None = None,
    schedule: str = DEFAULT_SCHEDULE,
) -> dict[str, Any]:
    """Spec -> plan dict (the part benchmarked by benchmarks/compile_scaling.py)."""
    # The compiler allocates many small acyclic objects; the cyclic collector would rescan
    # the whole (large) heap again and again. Nothing here creates reference cycles.
    enabled = gc.isenabled()
    gc.disable()
    try:
        return _compile_spec(spec, policy, memory_provider, profile_name, schedule)
    finally:
        if enabled:
            gc.enable()


def _compile_spec(spec, policy, memory_provider, profile_name, schedule=DEFAULT_SCHEDULE) -> dict[str, Any]:
    culling = cull(spec)
    passes = schedule_passes(culling.passes, schedule)  # default: declaration order minus culled passes
    if memory_provider is None:
        from rgraph.memory_requirements import ProfileMemoryRequirements

        memory_provider = ProfileMemoryRequirements.named(DEFAULT_PROFILE)
        profile_name = profile_name or DEFAULT_PROFILE
    passes = size_accels(spec, passes, memory_provider)
    used = memory.usages_by_resource(passes)
    spans = memory.lifetimes(passes)
    reqs = memory.requirements(spec.resources, used, spec.outputs, memory_provider)
    classes = memory.memory_classes(reqs)
    try:
        placement = memory.place_resources(spec.resources, reqs, classes, spans, policy, spec.outputs)
    except ValueError as exc:
        raise RGraphError.in_file("<command line>", f"--policy: {exc}") from None
    aliases = memory.alias_sources(placement, reqs, spans)
    culled_passes = {c.pass_name for c in culling.culled}
    culled_used = {
        r: u for r, u in memory.usages_by_resource([p for p in spec.passes if p.name in culled_passes]).items()
        if r not in reqs
    }
    culled_bytes = {r: v[0] for r, v in memory.requirements(spec.resources, culled_used, spec.outputs, memory_provider).items()}
    sync = synchronize(passes, spec.resources, aliases)
    plan = build_plan(
        spec, culling, passes, sync, placement, reqs, classes, spans, used, profile_name or "device",
        culled_bytes
    )
    if schedule != DEFAULT_SCHEDULE:
        plan["stats"]["schedule"] = schedule  # absent = declaration order
    return plan


def add_outputs(spec: Spec, names: Sequence[str]) -> None:
    """Append resources ``names`` to ``spec.outputs`` (a name already there is kept once)."""
    for name in names:
        if name not in spec.resources:
            raise RGraphError.in_file(
                "<command line>", f"extra output '{name}' is not a resource{did_you_mean(name, spec.resources)}"
            )
        if name not in spec.outputs:
            spec.outputs.append(name)


def compile_graph(
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
) -> dict[str, Any]:
    """Compile a graph file (or bundled graph name) into a plan dict.

    ``extra_outputs`` names resources kept as outputs besides the graph's own (their
    writers are not culled and the runtime reads them back), e.g. an HDR intermediate.
    ``sync="naive"`` transforms the plan with ``rgraph.compiler.naive_sync`` (a full barrier
    before every pass, one queue, no semaphores), for comparison.
    """
    front = frontend(graph, scene_path, params, size)
    add_outputs(front.spec, extra_outputs)
    provider = memory
    profile_name = None
    if provider is None and profile is not None:
        from rgraph.memory_requirements import ProfileMemoryRequirements

        provider = ProfileMemoryRequirements.named(profile)
        profile_name = provider.name
    chosen = policy or front.source.memory_policy or DEFAULT_POLICY
    plan = compile_spec(front.spec, policy=chosen, memory_provider=provider, profile_name=profile_name,
                        schedule=schedule)
    if camera:
        plan["camera"] = check_camera(front.scene, camera)
    return apply_sync_mode(plan, sync)


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


SYNC_MODES = ("normal", "naive")


def apply_sync_mode(plan: dict[str, Any], sync: str) -> dict[str, Any]:
    """``plan`` as is ("normal") or transformed by ``rgraph.compiler.naive_sync`` ("naive")."""
    if sync == "normal":
        return plan
    if sync == "naive":
        from rgraph.compiler.naive_sync import naive_sync

        return naive_sync(plan)
    raise RGraphError.in_file("<command line>", f"--sync expects one of {', '.join(SYNC_MODES)}, got '{sync}'")
