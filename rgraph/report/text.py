"""The terminal views, printed onto a rich console."""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.text import Text

from rgraph.report import barriers, memory, summary
from rgraph.report.table import print_lines, print_table

Plan = dict[str, Any]


def _heading(console: Console, title: str) -> None:
    console.print(Text(title, style="bold underline"))


def print_summary(console: Console, plan: Plan, timings: dict | None = None) -> None:
    """Header, schedule, culled passes (with measured GPU ms given ``timings``), dropped reads, stats."""
    print_lines(console, summary.header_lines(plan))
    console.print()
    print_table(console, summary.schedule_table(plan))
    print_table(console, summary.culled_table(plan, timings))
    if timings is not None:
        from rgraph.report.memory import culling_total_line

        total = culling_total_line(plan, timings)
        if total:
            print_lines(console, [total])
    print_table(console, summary.dropped_table(plan))
    _heading(console, "Stats")
    print_lines(console, summary.stats_lines(plan))


def print_barriers(console: Console, plan: Plan) -> None:
    """Every wait, barrier, release and signal in execution order."""
    _heading(console, "Barriers (execution order)")
    print_lines(console, barriers.barrier_lines(plan))
    print_lines(console, [barriers.barrier_totals(plan)])


def print_memory(console: Console, plan: Plan, timings: dict | None = None) -> None:
    """Resources, heaps, bytes per class and what culling saved."""
    print_table(console, memory.resources_table(plan))
    print_table(console, memory.heaps_table(plan))
    _heading(console, "Bytes per memory class")
    print_lines(console, memory.class_lines(plan) or ["  (no heaps)"])
    console.print()
    print_table(console, memory.culling_table(plan))
    total = memory.culling_total_line(plan, timings)
    if total:
        print_lines(console, [total])
