"""One sweep setting rendered in a worker process (``--workers``, ``--ray``).

The parent sends a :class:`RenderJob` per distinct setting; the worker compiles the setting
with its own device's memory requirements and renders it exactly as the one-process sweep
does (``runner._compile_all``, ``runner._render``),
then hands the rendering (plan, times, messages, images) back; a job made after the
reference rendered carries the reference's images, and its worker computes the metrics too.

A worker is a fresh interpreter: the job carries the parent's ``sys.path`` and the modules
that registered the graph's pass implementations there (a user's passes, a test fixture),
by name and file, and imports them first.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import importlib.util
import os
import signal
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rgraph.sweep.settings import Setting

#: Test-only fault injection, read by the parent (never from a graph file): ``LABEL@MARKER``
#: SIGKILLs the worker of setting LABEL once (it creates the file MARKER first; the retry finds
#: it); ``LABEL`` alone kills every attempt.
KILL_ENV = "RGRAPH_TEST_KILL_ONCE"


@dataclass(frozen=True)
class RenderJob:
    request: Any  # rgraph.sweep.runner.SweepRequest
    setting: Setting
    sys_path: tuple[str, ...]
    modules: tuple[tuple[str, str | None], ...]  # (name, file) of modules registering the graph's impls
    fault: str | None = None
    reference: Any = None  # the reference's Images once rendered: the worker compares with it
    timing_lock: str | None = None  # file locked around the timed frames (local workers sharing a GPU)
    error_maps: tuple[str, ...] = ()  # slugs whose error maps the worker draws (with the reference)


def implementation_modules(impls: set[str]) -> tuple[tuple[str, str | None], ...]:
    """(module, file) of the implementations ``impls`` registered in this process outside
    rgraph (whose own passes every process loads)."""
    from rgraph import impl

    modules = {impl._REGISTRY[name].__module__ for name in impls if name in impl._REGISTRY}
    out = []
    for name in sorted(modules):
        if name.startswith("rgraph.") or name in ("__main__", "__mp_main__"):
            continue
        out.append((name, getattr(sys.modules.get(name), "__file__", None)))
    return tuple(out)


def _graph_impls(request: Any) -> set[str]:
    from rgraph.resources import resolve_graph
    from rgraph.spec.loader import load_graph

    source = load_graph(resolve_graph(request.graph))
    return {p.model.impl for p in source.passes.values() if getattr(p.model, "impl", None)}


def job_maker(request: Any, env: Mapping[str, str] | None = None,
              timing_lock: str | None = None) -> Callable[[Setting, Any], RenderJob]:
    """``make(setting, reference_images)``: the job of one setting of ``request`` (graph and
    scene paths made absolute, the caller's ``sys.path`` and implementation modules;
    ``timing_lock``: :func:`timed_alone`)."""
    env = os.environ if env is None else env
    fault = env.get(KILL_ENV) or None
    request = dataclasses.replace(request, graph=_absolute(request.graph), scene=_absolute(request.scene))
    sys_path = tuple(p for p in sys.path if p)
    modules = implementation_modules(_graph_impls(request))

    def make(setting: Setting, reference: Any = None, error_maps: tuple[str, ...] = ()) -> RenderJob:
        reference = None if setting.label == "reference" else reference
        return RenderJob(request, setting, sys_path, modules, fault, reference, timing_lock,
                         error_maps if reference is not None else ())

    return make


def jobs(request: Any, settings: Mapping[Any, Setting], collector: Any = None,
         env: Mapping[str, str] | None = None, timing_lock: str | None = None) -> Iterator[tuple[Any, RenderJob]]:
    """(params key, job) per distinct setting, in the given order (the reference first).
    Read lazily: a job made once ``collector`` (:class:`rgraph.sweep.collect.Collector`) has
    the reference's images carries them, so its worker computes the metrics and draws the
    setting's error maps too."""
    make = job_maker(request, env, timing_lock)
    for key, setting in settings.items():
        yield key, collector_job(make, collector, key, setting)


def collector_job(make: Callable[..., RenderJob], collector: Any, key: Any, setting: Setting) -> RenderJob:
    """``make``'s job for ``setting`` with what ``collector`` has: the reference's images
    (once rendered) and the slugs of the settings of ``key`` whose error maps are kept."""
    if collector is None:
        return make(setting)
    return make(setting, collector.reference_images(), collector.extreme_slugs(key))


def _absolute(path: str | None) -> str | None:
    """A file path made absolute (a worker may start elsewhere); names (``surgery``) as given."""
    return str(Path(path).resolve()) if path and Path(path).is_file() else path


def _prepare(job: RenderJob) -> None:
    for entry in reversed(job.sys_path):
        if entry not in sys.path and Path(entry).exists():
            sys.path.insert(0, entry)
    for module, file in job.modules:
        if module in sys.modules:
            continue
        try:
            importlib.import_module(module)
        except ModuleNotFoundError:
            if not file:
                raise
            spec = importlib.util.spec_from_file_location(module, file)
            loaded = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
            sys.modules[module] = loaded
            spec.loader.exec_module(loaded)  # type: ignore[union-attr]


def _inject_fault(job: RenderJob) -> None:
    if not job.fault:
        return
    label, sep, marker = job.fault.partition("@")
    if label != job.setting.label:
        return
    if sep:
        if Path(marker).exists():
            return
        Path(marker).write_text(f"killed {label} once (pid {os.getpid()})\n")
    os.kill(os.getpid(), signal.SIGKILL)


def gpu_device_index(devices: Sequence[Any], gpu: int) -> int | None:
    """The Vulkan index of the ``gpu``-th GPU (discrete or integrated, in Vulkan's order)."""
    gpus = [d.index for d in devices if d.device_type in ("discrete", "integrated")]
    return gpus[gpu] if 0 <= gpu < len(gpus) else None


def _device_index(request: Any) -> int | None:
    """``--device`` when given; in a Ray GPU task, the Vulkan GPU of Ray's GPU id."""
    from rgraph.sweep.parallel import assigned_gpu

    if request.device is not None:
        return request.device
    gpu = assigned_gpu()
    if gpu is None:
        return None
    from rgraph.vk.device import list_physical_devices
    from rgraph.vk.instance import create_instance

    instance = create_instance(validate=False)
    try:
        return gpu_device_index(list_physical_devices(instance), gpu)
    finally:
        instance.destroy()


@contextlib.contextmanager
def timed_alone(path: str | None) -> Iterator[None]:
    """Hold the exclusive lock on file ``path`` (none: no lock): local workers take it around
    their warm-up, timed frames and read-back, so no other worker's frames share the GPU while
    one is timed; compiles, pipelines, uploads, PNG and metrics still overlap."""
    if not path:
        yield
        return
    import fcntl

    with open(path, "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


_DEVICES: dict[tuple[bool, int | None], Any] = {}  # kept open for a worker's next setting


def _open(validate: bool, device: int | None) -> Any:
    """The worker's device (``rgraph.open_device``), opened once and closed at exit."""
    import atexit

    from rgraph.api import open_device

    key = (validate, device)
    if key not in _DEVICES:
        gpu = _DEVICES[key] = open_device(validate=validate, device=device, verbose=False)
        atexit.register(gpu.close)
    return _DEVICES[key]


def _drop(validate: bool, device: int | None) -> None:
    import atexit

    gpu = _DEVICES.pop((validate, device), None)
    if gpu is not None:
        atexit.unregister(gpu.close)
        gpu.close()


def render_job(job: RenderJob) -> Any:
    """Compile and render one setting (in a worker process): a runner ``_Rendering``. The
    device stays open for the worker's next setting (``--workers`` with several settings per
    worker), as the one-process sweep renders every setting on one device; a failed setting
    closes it."""
    from rgraph.sweep.runner import _compile_all, _render

    _prepare(job)
    _inject_fault(job)
    request = job.request
    index = _device_index(request)
    if index != request.device:
        request = dataclasses.replace(request, device=index)
    gpu = _open(request.validate, request.device)
    try:
        (plan,) = _compile_all(request, [job.setting], gpu).values()
        rendering = _render(request, plan, gpu, timed_alone(job.timing_lock))
    except BaseException:
        _drop(request.validate, request.device)
        raise
    if job.reference is not None:
        from rgraph.sweep.compare import compare

        rendering.compared = compare(job.reference, rendering.images)
        ref, test = job.reference.ldr, rendering.images.ldr
        if job.error_maps and ref is not None and test is not None and ref.shape == test.shape:
            from rgraph.sweep.plots import error_map_pngs

            rendering.error_maps = {slug: error_map_pngs(slug, ref, test) for slug in job.error_maps}
    return rendering
