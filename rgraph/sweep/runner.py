"""Compile and execute every setting of a sweep; time it and compare it with the reference.

Settings with equal resolved params are rendered once, here one after the other (reference
first) or each in a worker process (``executor``: :mod:`rgraph.sweep.parallel`,
:mod:`rgraph.sweep.remote`); :mod:`rgraph.sweep.collect` compares and writes every rendering
as it comes, in any order, and orders the rows as the settings.
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rgraph.resources import resolve_graph
from rgraph.spec.loader import load_graph
from rgraph.sweep import images as image_io
from rgraph.sweep.compare import Images
from rgraph.sweep.settings import Knob, Setting, expand, numeric_key, params_key, resolved

if TYPE_CHECKING:
    from rgraph.sweep.parallel import Executor


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
    warmup_s: float | None = None  # None: the device's default (api.Gpu.default_warmup_s); see warmup_frames


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
    failures: dict[str, str] = field(default_factory=dict)  # setting label -> why it was not rendered
    plans: dict[tuple, dict] = field(default_factory=dict)  # params key -> compiled plan
    knob_passes: dict[str, list[str]] = field(default_factory=dict)  # knob -> passes it changes (affected.py)

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
    plan: dict
    pass_ms: dict[str, float | None]
    total_ms: float | None
    messages: list[str]
    device: str
    images: Images
    notes: list[str] = field(default_factory=list)
    params_read: dict[str, list[str]] = field(default_factory=dict)  # pass -> params its impl looked up
    png: bytes | None = None  # the display image as PNG (encoded where it rendered: a worker, in parallel)
    compared: tuple[dict[str, float | None], list[str]] | None = None  # metrics, when a worker had the reference
    error_maps: dict[str, dict[str, bytes]] = field(default_factory=dict)  # slug -> drawn maps (a worker's)


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


@dataclass
class Prepared:
    """A sweep ready to render: its distinct settings (params key -> first setting with
    those params, the reference first) and the collector that takes their renderings."""

    request: SweepRequest
    distinct: dict[tuple, Setting]
    collector: Any  # rgraph.sweep.collect.Collector


def prepare(request: SweepRequest, out_dir: Path) -> Prepared:
    """Expand ``request``'s settings (bad knobs fail here, before anything renders)."""
    from rgraph.sweep.collect import Collector

    source = load_graph(resolve_graph(request.graph))
    settings = expand(source, request.knobs, base=request.base, reference=request.reference, grid=request.grid)
    resolved_params = {s.label: resolved(source, s.overrides) for s in settings}
    distinct: dict[tuple, Setting] = {}
    for s in settings:
        distinct.setdefault(params_key(resolved_params[s.label]), s)
    return Prepared(request, distinct, Collector(request, settings, resolved_params, out_dir))


def run_sweep(request: SweepRequest, out_dir: Path, *, progress: bool = True,
              executor: Executor | None = None) -> SweepResult:
    """Render every setting of ``request``; write images and error maps under ``out_dir``.

    ``executor`` (``rgraph.sweep.parallel``): every distinct setting in its own worker
    process, compiled and rendered there; a setting that fails twice is reported in
    ``SweepResult.failures`` and its row left empty. Without one, every setting renders here,
    one after the other, and the first failure raises. Several sweeps through one pool of
    workers: :func:`rgraph.sweep.pool.run_groups`."""
    sweep = prepare(request, out_dir)
    distinct, collector = sweep.distinct, sweep.collector
    with progress_bar(progress, len(distinct)) as bar:
        if executor is None:
            from rgraph.api import open_device

            with open_device(validate=request.validate, device=request.device, verbose=False) as gpu:  # one device
                plans = _compile_all(request, list(distinct.values()), gpu)
                for key, s in distinct.items():
                    bar.step(s.label)
                    collector.add(key, _render(request, plans[key], gpu))
        else:
            from rgraph.sweep.remote import jobs, render_job

            for outcome in executor.run(render_job, jobs(request, distinct, collector,
                                                         timing_lock=executor.timing_lock)):
                collector.add(outcome.key, outcome.value, outcome.error)
                bar.finished(distinct[outcome.key].label + ("" if outcome.ok else " (failed)"))
    return collector.result()


def _compile_all(request: SweepRequest, settings: list[Setting], gpu: Any) -> dict[tuple, dict]:
    """Plans by params key, compiled with the memory requirements of ``gpu`` (``rgraph.open_device``),
    the device that renders them."""
    from rgraph.compiler.pipeline import compile_graph

    source = load_graph(resolve_graph(request.graph))
    plans: dict[tuple, dict] = {}
    memory = gpu.memory_requirements()
    for s in settings:
        plans[params_key(resolved(source, s.overrides))] = compile_graph(
            request.graph, scene_path=request.scene, params=s.overrides, size=request.size,
            policy=request.policy, memory=memory, extra_outputs=[request.hdr] if request.hdr else [])
    return plans


#: Untimed warm-up frames per second of ``--warmup`` (``warmup_frames``).
WARMUP_FPS = 200


def warmup_frames(request: SweepRequest, gpu: Any) -> int:
    """Untimed frames before a setting's timed ones: ``--warmup`` seconds (default the
    device's ``default_warmup_s``: 0.3 s on a GPU, none on a CPU device) times
    :data:`WARMUP_FPS`, the same count for every setting. Plans that carry no state between
    frames then start their content at frame 0 again (``Executable.warm_up``); for a plan
    that does, a wall-time warm-up would run a different number of frames per setting and each
    image would show another moment (errors that no knob caused, outputs that differ run to
    run); a count keeps them the same."""
    seconds = gpu.default_warmup_s if request.warmup_s is None else request.warmup_s
    return max(1, round(seconds * WARMUP_FPS)) if seconds > 0 else 0


def _render(request: SweepRequest, plan: dict, gpu: Any, timing: Any = None) -> _Rendering:
    """Load ``plan`` on ``gpu``, run :func:`warmup_frames` untimed frames, time
    ``request.frames`` frames and read back; ``timing``: a context manager held around the
    warm-up, the timed frames and the read-back (the lock that keeps other local workers'
    frames off the GPU meanwhile: :mod:`rgraph.sweep.remote`)."""
    executable = gpu.load(plan)
    warm = warmup_frames(request, gpu)
    with timing or contextlib.nullcontext():
        result = executable.run_and_check(request.frames, check_data=False, read_outputs=True, warmup_s=0.0,
                                          warmup_frames=warm)
    arrays = image_io.output_arrays(result)
    outputs = image_io.output_image_resources(plan)
    ldr = hdr = None
    notes: list[str] = []
    if outputs and outputs[0]["name"] in arrays:
        ldr = image_io.display(arrays[outputs[0]["name"]], outputs[0]["format"])
    if request.hdr and request.hdr in arrays:
        hdr = image_io.rgb(arrays[request.hdr])
    elif request.hdr:
        notes.append(f"HDR metrics not computed: the run gave no float image of '{request.hdr}'")
    timings = result.timings or {}
    pass_ms = {p["name"]: timings.get("passes", {}).get(p["name"]) for p in plan["passes"]}
    return _Rendering(plan, pass_ms, timings.get("total_ms"), [str(m) for m in result.messages],
                      result.device_name, Images(ldr, hdr), notes, result.params_read,
                      None if ldr is None else image_io.png_bytes(ldr))


class progress_bar:
    """A rich progress bar on stderr (or nothing): ``step`` names the next rendering here,
    ``finished`` counts one that a worker finished."""

    def __init__(self, enabled: bool, total: int) -> None:
        self.enabled, self.total = enabled, total
        self.bar: Any = None
        self.task: Any = None

    def __enter__(self) -> progress_bar:
        if self.enabled:
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

            self.bar = Progress(TextColumn("sweep"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                                TextColumn("{task.description}"), console=Console(stderr=True))
            self.bar.start()
            self.task = self.bar.add_task("", total=self.total)
        return self

    def finished(self, label: str) -> None:
        """A rendering finished elsewhere (a worker): advance by one."""
        if self.bar is not None:
            self.bar.update(self.task, advance=1, description=label)

    def step(self, label: str) -> None:
        if self.bar is not None:
            done = self.bar.tasks[0].description != ""
            self.bar.update(self.task, advance=1 if done else 0, description=label)

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.update(self.task, completed=self.total, description="done")
            self.bar.stop()
