"""The ``--memory`` view: resources and their placement, heaps, and what culling saved."""

from __future__ import annotations

from typing import Any

from rgraph.report.fmt import align_up, bytes_exact, extent, human_bytes, plural
from rgraph.report.table import TableData

Plan = dict[str, Any]


def pass_name(plan: Plan, index: int | None) -> str:
    """The name of the executed pass at ``index`` (``?`` when out of range)."""
    passes = plan["passes"]
    if index is None:
        return "-"
    return passes[index]["name"] if 0 <= index < len(passes) else "?"


def lifetime_cell(plan: Plan, r: dict[str, Any]) -> str:
    """``2..4 (depth_prepass..lighting)``; ``unused`` when the resource has no pass."""
    first, last = r.get("first"), r.get("last")
    if first is None or last is None:
        return "unused"
    return f"{first}..{last} ({pass_name(plan, first)}..{pass_name(plan, last)})"


def _shape_cell(r: dict[str, Any]) -> str:
    if r.get("kind", "image") != "image":
        size = r.get("size_bytes")
        return f"{size} B requested" if size is not None else "-"
    extras = []
    for key, unit in (("mips", "mips"), ("layers", "layers")):
        if (r.get(key) or 1) > 1:
            extras.append(f"{r[key]} {unit}")
    if (r.get("samples") or 1) > 1:
        extras.append(f"{r['samples']}x MSAA")
    text = extent(r.get("extent"))
    return f"{text} ({', '.join(extras)})" if extras else text


def resources_table(plan: Plan) -> TableData:
    """One row per resource with its size, lifetime and placement."""
    rows = []
    for r in plan.get("resources") or []:
        heap = r.get("heap")
        rows.append(
            (
                r["name"],
                r.get("kind") or "-",
                r.get("format") or "-",
                _shape_cell(r),
                "-" if r.get("bytes") is None else str(r["bytes"]),
                human_bytes(r.get("bytes")),
                str(r.get("alignment") if r.get("alignment") is not None else "-"),
                r.get("lifetime") or "-",
                lifetime_cell(plan, r),
                "-" if heap is None else str(heap),
                "-" if r.get("offset") is None else str(r["offset"]),
                r.get("memory_class") or "-",
            )
        )
    return TableData(
        f"Resources ({len(rows)})",
        ("resource", "kind", "format", "extent", "bytes", "size", "align", "lifetime", "passes", "heap", "offset",
         "memory class"),
        rows,
        right=frozenset({"bytes", "size", "align", "heap", "offset"}),
    )


def _aligned(r: dict[str, Any]) -> int:
    size = r.get("bytes") or 0
    alignment = r.get("alignment") or 1
    return align_up(size, alignment)


def heaps_table(plan: Plan) -> TableData:
    """One row per heap: size, class, and how much its residents would take unaliased."""
    residents: dict[int, list[dict[str, Any]]] = {}
    for r in plan.get("resources") or []:
        if r.get("heap") is not None:
            residents.setdefault(r["heap"], []).append(r)
    rows = []
    for h in plan.get("heaps") or []:
        members = residents.get(h["id"], [])
        unaliased = sum(_aligned(r) for r in members)
        rows.append(
            (
                str(h["id"]),
                h.get("memory_class") or "-",
                bytes_exact(h["bytes"]),
                str(h.get("alignment", "-")),
                str(len(members)),
                bytes_exact(unaliased),
                ", ".join(r["name"] for r in members) or "-",
            )
        )
    return TableData(
        f"Heaps ({len(rows)})",
        ("heap", "memory class", "bytes", "align", "resources", "unaliased", "residents"),
        rows,
        right=frozenset({"heap", "bytes", "align", "resources", "unaliased"}),
    )


def class_lines(plan: Plan) -> list[str]:
    """Heap bytes summed per memory class."""
    totals: dict[str, list[int]] = {}
    for h in plan.get("heaps") or []:
        entry = totals.setdefault(h.get("memory_class") or "-", [0, 0])
        entry[0] += h["bytes"]
        entry[1] += 1
    return [
        f"{cls:<24} {bytes_exact(total)} in {plural(count, 'heap')}"
        for cls, (total, count) in sorted(totals.items())
    ]


def culling_table(plan: Plan) -> TableData:
    """Per culled pass the resources only it used, and their bytes (when the plan lists them)."""
    rows = []
    for c in plan.get("culled") or []:
        names = c.get("resources")
        rows.append(
            (
                c["pass"],
                c.get("reason") or "-",
                "(not listed)" if names is None else (", ".join(names) or "(none)"),
                "-" if c.get("bytes") is None else bytes_exact(c["bytes"]),
            )
        )
    return TableData(
        f"Saved by culling ({plural(len(rows), 'culled pass')})",
        ("culled pass", "reason", "resources only it used", "bytes"),
        rows,
        right=frozenset({"bytes"}),
    )


def culled_resource_bytes(plan: Plan) -> dict[str, int]:
    """Bytes of each resource only culled passes used, derived from the culled entries.

    An entry's ``bytes`` is the sum over its ``resources``; two culled passes that share a
    resource (``sss_blur_h`` and ``sss_blur_v`` both use ``sss_tmp``) list it twice, so the
    total counts each resource once: single-resource entries give a resource's bytes, and an
    entry whose other resources are known gives the rest.
    """
    entries = [(list(c["resources"]), c["bytes"]) for c in plan.get("culled") or []
               if c.get("resources") is not None and c.get("bytes") is not None]
    known: dict[str, int] = {}
    progress = True
    while progress:
        progress = False
        for names, total in entries:
            unknown = [n for n in dict.fromkeys(names) if n not in known]
            if len(unknown) == 1:
                known[unknown[0]] = total - sum(known[n] for n in dict.fromkeys(names) if n in known)
                progress = True
    return known


def culled_bytes_total(plan: Plan) -> int | None:
    """Bytes culling saved, each resource counted once (None when the plan lists no bytes)."""
    entries = [c for c in plan.get("culled") or [] if c.get("bytes") is not None]
    if not entries:
        return None
    known = culled_resource_bytes(plan)
    names = {n for c in entries for n in c.get("resources") or []}
    if names <= known.keys() and all(c.get("resources") is not None for c in entries):
        return sum(known[n] for n in names)
    return sum(c["bytes"] for c in entries)  # not derivable per resource: an upper bound


def culling_total_line(plan: Plan, timings: dict | None = None) -> str | None:
    """The total saved by culling (bytes; GPU ms per frame when ``timings`` of a run of the
    full scene are given), or ``None`` when there is nothing to report."""
    from rgraph.report.summary import culled_ms

    saved = culled_bytes_total(plan)
    counted = [saved] if saved is not None else []
    times = [culled_ms(timings, c["pass"]) for c in plan.get("culled") or []]
    measured = [t for t in times if t is not None]
    parts = []
    if counted:
        parts.append(bytes_exact(sum(counted)))
    if measured:
        device = (timings or {}).get("device") or "the timed device"
        parts.append(f"{sum(measured):.3f} ms of GPU time per frame (measured on {device})")
    if not parts:
        return None
    return "culling saved " + " and ".join(parts)
