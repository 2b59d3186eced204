"""Compile and execute every setting of a sweep; time it and compare it with the reference.

Settings with equal resolved params are rendered once. The reference renders first; each
later rendering is compared, written as PNG and dropped, so memory holds two images.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rgraph.resources import resolve_graph
from rgraph.spec.loader import load_graph
from rgraph.sweep import images as image_io
from rgraph.sweep.compare import Images, compare
from rgraph.sweep.settings import Knob, Setting, expand, numeric_key, params_key, resolved

if TYPE_CHECKING:
    from rgraph.plan import Plan


@dataclass
class SweepRequest:
    graph: str
    knobs: list[Knob]
    scene: str | None = None
    base: dict[str, str] = field(default_factory=dict)  # -p overrides under every setting
    reference: dict[str, str] = field(default_factory=dict)
    grid: bool = False
    size: tuple[int, int] = (640, 360)
    frames: int = 8
    device: int | None = None
    policy: str | None = None
    hdr: str | None = None  # an intermediate image read back for HDR metrics
    validate: bool = False


@dataclass
class Row:
    """One setting's figures."""

    setting: Setting
    params: dict[str, Any]  # resolved
    pass_ms: dict[str, float | None]
    total_ms: float | None
    metrics: dict[str, float | None]
    messages: list[str]  # validation messages of its rendering
    image: str | None  # PNG path relative to the output folder
    rendering: int  # index of the rendering it shares with equal settings


@dataclass
class SweepResult:
    request: SweepRequest
    graph_name: str
    scene: str | None
    device: str
    defaults: dict[str, Any]  # resolved params of the default setting (base -p applied)
    rows: list[Row]
    pass_names: list[str]  # per-pass columns, in executed order
    notes: list[str]
    error_maps: dict[str, list[str]]  # setting label -> PNG paths (relative)
    output_name: str | None  # the LDR image compared
    reference_params: dict[str, Any] = field(default_factory=dict)

    @property
    def renderings(self) -> int:
        return len({r.rendering for r in self.rows})

    def messages(self) -> list[tuple[str, str]]:
        """(setting label, message) of every rendering, each rendering once."""
        seen: set[int] = set()
        out = []
        for row in self.rows:
            if row.rendering not in seen:
                seen.add(row.rendering)
                out += [(row.setting.label, m) for m in row.messages]
        return out

    def rows_for_knob(self, knob: str) -> list[Row]:
        """Rows that vary ``knob`` (grid: every knob row), plus the default row when no
        such row already renders the defaults."""
        rows = [r for r in self.rows if knob in r.setting.varied]
        keys = {params_key(r.params) for r in rows}
        default = next((r for r in self.rows if r.setting.role == "default"), None)
        if default is not None and params_key(default.params) not in keys and not self.request.grid:
            rows.append(default)
        return rows


@dataclass
class _Rendering:
    plan: Plan
    pass_ms: dict[str, float | None]
    total_ms: float | None
    messages: list[str]
    device: str
    images: Images


Compile = Callable[[Setting], dict]
Progress = Callable[[str], None]


def extreme_labels(settings: Sequence[Setting], knobs: Sequence[Knob], grid: bool) -> list[str]:
    """Settings whose error maps are kept: each knob's lowest and highest value (grid: the
    all-lowest and all-highest combinations)."""
    if grid:
        low = {k.name: min(k.values, key=numeric_key) for k in knobs}
        high = {k.name: max(k.values, key=numeric_key) for k in knobs}
        wanted = [low, high]
    else:
        wanted = [{k.name: v} for k in knobs for v in (min(k.values, key=numeric_key), max(k.values, key=numeric_key))]
    labels: list[str] = []
    for varied in wanted:
        for s in settings:
            if s.role == "knob" and s.varied == varied and s.label not in labels:
                labels.append(s.label)
    return labels


def run_sweep(request: SweepRequest, out_dir: Path, *, progress: bool = True) -> SweepResult:
    """Render every setting of ``request`` on one device; write images and error maps under ``out_dir``."""
    from rgraph.api import open_device

    source = load_graph(resolve_graph(request.graph))
    settings = expand(source, request.knobs, base=request.base, reference=request.reference, grid=request.grid)
    resolved_params = {s.label: resolved(source, s.overrides) for s in settings}
    distinct: dict[tuple, Setting] = {}
    for s in settings:
        distinct.setdefault(params_key(resolved_params[s.label]), s)
    with open_device(validate=request.validate, device=request.device, verbose=False) as gpu:  # one device
        plans = _compile_all(request, list(distinct.values()), gpu)
        return _render_all(request, out_dir, settings, resolved_params, distinct, plans, gpu, progress)


def _render_all(request: SweepRequest, out_dir: Path, settings: list[Setting], resolved_params: dict,
                distinct: dict[tuple, Setting], plans: dict[tuple, Plan], gpu: Any, progress: bool) -> SweepResult:
    from rgraph.sweep import plots  # matplotlib: only when sweeping

    extremes = set(extreme_labels(settings, request.knobs, request.grid))
    notes: list[str] = []
    renderings: dict[tuple, _Rendering] = {}
    rows: list[Row] = []
    error_maps: dict[str, list[str]] = {}
    uses = Counter(params_key(resolved_params[s.label]) for s in settings)
    reference_key = params_key(resolved_params["reference"])
    out_dir.mkdir(parents=True, exist_ok=True)
    with _progress_bar(progress, len(distinct)) as step:
        reference: _Rendering | None = None
        for s in settings:
            key = params_key(resolved_params[s.label])
            if key not in renderings:
                step(s.label)
                renderings[key] = _render(request, plans[key], notes, gpu)
            rendering = renderings[key]
            if reference is None:
                reference = rendering
            values, more = compare(reference.images, rendering.images)
            notes.extend(n for n in (f"{s.label}: {m}" for m in more) if n not in notes)
            image = None
            if rendering.images.ldr is not None:
                image = f"images/{s.slug}.png"
                image_io.save_png(out_dir / image, rendering.images.ldr)
            if s.label in extremes and reference.images.ldr is not None and rendering.images.ldr is not None \
                    and reference.images.ldr.shape == rendering.images.ldr.shape:
                error_maps[s.label] = plots.write_error_maps(out_dir, s.slug, reference.images.ldr,
                                                             rendering.images.ldr)
            rows.append(Row(s, resolved_params[s.label], rendering.pass_ms, rendering.total_ms, values,
                            rendering.messages, image, list(renderings).index(key)))
            uses[key] -= 1
            if uses[key] == 0 and key != reference_key:
                rendering.images = Images(None, None)  # compared and written: free the pixels
    first_plan = plans[reference_key]
    pass_names: list[str] = []
    for plan in plans.values():
        pass_names += [p.name for p in plan.passes if p.name not in pass_names]
    order = {p.name: i for i, p in enumerate(first_plan.passes)}
    pass_names.sort(key=lambda n: order.get(n, len(order)))
    outputs = image_io.output_image_resources(first_plan)
    return SweepResult(
        request=request, graph_name=first_plan.graph, scene=first_plan.scene,
        device=next(iter(renderings.values())).device, defaults=resolved_params["default"], rows=rows,
        pass_names=pass_names, notes=notes, error_maps=error_maps,
        output_name=outputs[0].name if outputs else None, reference_params=resolved_params["reference"],
    )


def _compile_all(request: SweepRequest, settings: list[Setting], gpu: Any) -> dict[tuple, Plan]:
    """Plans by params key, compiled with the memory requirements of ``gpu``, the device that renders them."""
    from rgraph.compiler.pipeline import compile_graph_plan

    source = load_graph(resolve_graph(request.graph))
    plans: dict[tuple, Plan] = {}
    memory = gpu.memory_requirements()
    for s in settings:
        plans[params_key(resolved(source, s.overrides))] = compile_graph_plan(
            request.graph, scene_path=request.scene, params=s.overrides, size=request.size,
            policy=request.policy, memory=memory, extra_outputs=[request.hdr] if request.hdr else [])
    return plans


def _render(request: SweepRequest, plan: Plan, notes: list[str], gpu: Any) -> _Rendering:
    result = gpu.load(plan).run_and_check(request.frames, check_data=False, read_outputs=True)
    arrays = image_io.output_arrays(result)
    outputs = image_io.output_image_resources(plan)
    ldr = hdr = None
    if outputs and outputs[0].name in arrays:
        ldr = image_io.display(arrays[outputs[0].name], outputs[0].format)
    if request.hdr and request.hdr in arrays:
        hdr = image_io.rgb(arrays[request.hdr])
    elif request.hdr:
        note = f"HDR metrics not computed: the run gave no float image of '{request.hdr}'"
        if note not in notes:
            notes.append(note)
    timings = result.timings or {}
    pass_ms = {p.name: timings.get("passes", {}).get(p.name) for p in plan.passes}
    return _Rendering(plan, pass_ms, timings.get("total_ms"), [str(m) for m in result.messages],
                      result.device_name, Images(ldr, hdr))


class _progress_bar:
    """A rich progress bar on stderr (or nothing); calling it names the next rendering."""

    def __init__(self, enabled: bool, total: int) -> None:
        self.enabled, self.total = enabled, total
        self.bar: Any = None
        self.task: Any = None

    def __enter__(self) -> Progress:
        if self.enabled:
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

            self.bar = Progress(TextColumn("sweep"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                TextColumn("{task.description}"), console=Console(stderr=True))
            self.bar.start()
            self.task = self.bar.add_task("", total=self.total)
        return self.step

    def step(self, label: str) -> None:
        if self.bar is not None:
            done = self.bar.tasks[0].description != ""
            self.bar.update(self.task, advance=1 if done else 0, description=label)

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.update(self.task, completed=self.total, description="done")
            self.bar.stop()
