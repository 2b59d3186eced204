"""Several sweeps ("groups") through one pool of worker processes.

Every group's reference is submitted first; then, whenever a worker is free, the next
setting of the first group (in the given order) whose reference has rendered (its jobs carry
the reference's images, so their workers compute the metrics), else of the first group with
settings left. The pool thus never waits for one group's reference while any group has
settings left, and groups finish roughly in order (a run cut short keeps the first). Every
rendering goes to its own group's collector (:mod:`rgraph.sweep.collect`), and the moment a
group's last rendering lands its :class:`~rgraph.sweep.runner.SweepResult` is handed to
``done`` (which writes its outputs), so a run cut short keeps the groups that finished.

A group's outputs are those of its own ``rgraph sweep`` except measured times
(:mod:`rgraph.sweep.same`): the settings, the collector and the writers are the same code.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rgraph.sweep.parallel import Executor
from rgraph.sweep.runner import Prepared, SweepRequest, SweepResult, prepare, progress_bar


@dataclass(frozen=True)
class Group:
    """One sweep of a multi-group run: its name, request and output folder."""

    name: str
    request: SweepRequest
    out_dir: Path


Done = Callable[[Group, "SweepResult | Exception"], None]


def _items(groups: list[Group], sweeps: dict[str, Prepared], timing_lock: str | None) -> Iterator[tuple[tuple[str, tuple], Any]]:
    """(group name, params key) and job of every distinct setting: all references first, then
    the first group (in the given order) whose reference rendered and that has settings left,
    else the first with settings left. Read lazily by the executor, one item per free worker."""
    from rgraph.sweep.remote import collector_job, job_maker

    makers = {g.name: job_maker(g.request, timing_lock=timing_lock) for g in groups}
    left: dict[str, deque[tuple]] = {}
    for g in groups:
        sweep = sweeps[g.name]
        reference = sweep.collector.reference_key
        left[g.name] = deque(k for k in sweep.distinct if k != reference)
        yield (g.name, reference), makers[g.name](sweep.distinct[reference])
    while any(left.values()):
        waiting = [g.name for g in groups if left[g.name]]
        ready = [n for n in waiting if sweeps[n].collector.reference_images() is not None]
        name = (ready or waiting)[0]
        key = left[name].popleft()
        sweep = sweeps[name]
        yield (name, key), collector_job(makers[name], sweep.collector, key, sweep.distinct[key])


def run_groups(groups: list[Group], executor: Executor, *, done: Done | None = None,
               progress: bool = False) -> dict[str, SweepResult | Exception]:
    """Render every group's settings through ``executor``'s one pool; per group its result,
    or the error when every one of its settings failed. Bad knobs of any group fail before
    anything renders. A setting that fails twice is reported in its group's
    ``SweepResult.failures``; the others, in every group, still render."""
    from rgraph.vk.errors import ExecutionError

    names = [g.name for g in groups]
    if len(set(names)) != len(names):
        raise ValueError(f"group names must be unique: {names}")
    sweeps = {g.name: prepare(g.request, g.out_dir) for g in groups}
    by_name = {g.name: g for g in groups}
    left = {name: len(sweep.distinct) for name, sweep in sweeps.items()}
    results: dict[str, SweepResult | Exception] = {}
    from rgraph.sweep.remote import render_job

    with progress_bar(progress, sum(left.values())) as bar:
        for outcome in executor.run(render_job, _items(groups, sweeps, executor.timing_lock)):
            name, key = outcome.key
            sweep = sweeps[name]
            sweep.collector.add(key, outcome.value, outcome.error)
            bar.finished(f"{name}: {sweep.distinct[key].label}" + ("" if outcome.ok else " (failed)"))
            left[name] -= 1
            if left[name] == 0:
                try:
                    results[name] = sweep.collector.result()
                except ExecutionError as exc:  # every setting of the group failed
                    results[name] = exc
                if done is not None:
                    done(by_name[name], results[name])
    return {name: results[name] for name in names}
