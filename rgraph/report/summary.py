"""The default view: header, schedule, culled passes, dropped reads and stats."""

from __future__ import annotations

from typing import Any

from rgraph.report.fmt import bytes_exact, human_bytes, param_value, percent, plural
from rgraph.report.table import TableData

Plan = dict[str, Any]


def header_lines(plan: Plan) -> list[str]:
    """``key  value`` lines describing what the plan was compiled for."""
    size = plan.get("size")
    params = plan.get("params") or {}
    stats = plan.get("stats") or {}
    source = plan.get("source")
    graph = plan.get("graph") or "?"
    rows = [
        ("graph", f"{graph} ({source})" if source and source != graph else graph),
        ("scene", plan.get("scene") or "(none)"),
        ("size", f"{size[0]}x{size[1]}" if size else "-"),
        ("params", " ".join(f"{k}={param_value(params[k])}" for k in sorted(params)) or "(defaults)"),
        ("device", plan.get("device_profile") or "-"),
        ("policy", stats.get("policy") or "-"),
        ("queues", ", ".join(plan.get("queues") or []) or "-"),
    ]
    if plan.get("outputs"):
        rows.append(("outputs", ", ".join(plan["outputs"])))
    features = plan.get("features") or {}
    if features:
        rows.append(("features", " ".join(f"{k}={param_value(features[k])}" for k in sorted(features))))
    return [f"{key:<8} {value}" for key, value in rows]


def _sync_cell(p: dict[str, Any]) -> str:
    waits = [f"wait {w['queue']}>={w['value']}" for w in p.get("waits") or []]
    signals = [f"signal {s['queue']}={s['value']}" for s in p.get("signals") or []]
    return ", ".join(waits + signals)


def schedule_table(plan: Plan) -> TableData:
    """One row per executed pass, in order."""
    rows = []
    for pos, p in enumerate(plan["passes"]):
        barriers = len(p.get("barriers") or [])
        releases = len(p.get("releases") or [])
        rows.append(
            (
                str(p.get("index", pos)),
                p["name"],
                p.get("kind") or "-",
                p.get("queue") or "graphics",
                p.get("impl") or "probe",
                str(len(p.get("accesses") or [])),
                f"{barriers}+{releases} rel" if releases else str(barriers),
                _sync_cell(p),
            )
        )
    return TableData(
        f"Schedule ({plural(len(rows), 'pass')})",
        ("#", "pass", "kind", "queue", "impl", "accesses", "barriers", "waits/signals"),
        rows,
        right=frozenset({"#", "accesses", "barriers"}),
    )


def culled_ms(timings: dict | None, pass_name: str) -> float | None:
    """A culled pass's median GPU ms in ``timings`` (``rgraph run --timings`` of a scene that kept it)."""
    if not timings:
        return None
    value = (timings.get("passes") or {}).get(pass_name)
    return float(value) if isinstance(value, (int, float)) else None


def culled_table(plan: Plan, timings: dict | None = None) -> TableData:
    """Passes the compiler removed, and why (and their measured GPU ms, given ``timings``)."""
    culled = plan.get("culled") or []
    if timings is None:
        rows = [(c["pass"], c.get("reason") or "-") for c in culled]
        return TableData(f"Culled passes ({len(rows)})", ("pass", "reason"), rows)
    rows = []
    for c in culled:
        ms = culled_ms(timings, c["pass"])
        rows.append((c["pass"], c.get("reason") or "-", "-" if ms is None else f"{ms:.3f}"))
    return TableData(f"Culled passes ({len(rows)})", ("pass", "reason", "GPU ms saved"), rows,
                     right=frozenset({"GPU ms saved"}))


def dropped_table(plan: Plan) -> TableData:
    """Optional reads the compiler dropped, and why."""
    rows = [(d["pass"], d["resource"], d.get("reason") or "-") for d in plan.get("dropped_reads") or []]
    return TableData(f"Dropped optional reads ({len(rows)})", ("pass", "resource", "reason"), rows)


def counted_barriers(plan: Plan) -> tuple[int, int]:
    """(barriers before passes, queue-family releases after passes) as listed in the passes."""
    passes = plan["passes"]
    return (
        sum(len(p.get("barriers") or []) for p in passes),
        sum(len(p.get("releases") or []) for p in passes),
    )


def stats_lines(plan: Plan) -> list[str]:
    """Barrier and memory figures, in MiB with exact bytes where they matter."""
    stats = plan.get("stats") or {}
    listed, releases = counted_barriers(plan)
    barriers = stats.get("barriers", listed)
    barrier_text = str(barriers)
    if releases:
        barrier_text += f" + {plural(releases, 'queue-family release')}"
    if barriers != listed:
        barrier_text += f" [passes list {listed}]"
    peak = stats.get("peak_bytes")
    lower = stats.get("lower_bound_bytes")
    unaliased = stats.get("unaliased_bytes")
    allocations = stats.get("allocations", len(plan.get("heaps") or []))
    rows = [("barriers", barrier_text), ("semaphores", str(stats.get("semaphores", "-")))]
    if peak is not None:
        rows.append(("peak", f"{bytes_exact(peak)} in {plural(allocations, 'allocation')}"))
    if lower is not None:
        ratio = f", peak/lower bound {peak / lower:.3f}" if peak is not None and lower else ""
        rows.append(("lower bound", f"{bytes_exact(lower)}{ratio}"))
    if unaliased is not None:
        rows.append(("unaliased", bytes_exact(unaliased)))
        if peak is not None:
            saved = unaliased - peak
            rows.append(("saving", f"{percent(saved, unaliased)} ({human_bytes(saved)}) vs unaliased"))
    return [f"{key:<12} {value}" for key, value in rows]
