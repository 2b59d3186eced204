"""HTML report sections built from the plan's passes: the per-pass table of accesses and
barriers (each pass an anchor ``#pass-NAME``), the culled passes and the resources
(``#res-NAME``)."""

from __future__ import annotations

from html import escape
from typing import Any

from rgraph.report.fmt import bytes_exact, flags, human_bytes, subresource
from rgraph.report.memory import culled_bytes_total, culled_resource_bytes, lifetime_cell
from rgraph.report.summary import culled_ms

Plan = dict[str, Any]


def anchor(prefix: str, name: str) -> str:
    return f"{prefix}-{escape(name, quote=True)}"


def res_link(name: str) -> str:
    return f'<a href="#{anchor("res", name)}">{escape(name)}</a>'


def pass_link(name: str) -> str:
    return f'<a href="#{anchor("pass", name)}">{escape(name)}</a>'


def _table(columns: tuple[str, ...], rows: list[list[str]], cls: str = "") -> str:
    """Cells are HTML already (escape before)."""
    head = "".join(f"<th>{escape(c)}</th>" for c in columns)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return f'<table class="{cls}"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'


def _fl(names: Any) -> str:
    """Stage/access flags, breakable after each ``|``."""
    return escape(flags(names)).replace("|", "|<wbr>")


def _state(s: dict[str, Any]) -> str:
    return (f"{_fl(s.get('stages'))}<br><span class=\"acc\">{_fl(s.get('access'))}</span>"
            f"<br><span class=\"lay\">{escape(s.get('layout') or '-')}</span>")


def _barrier_rows(items: list[dict[str, Any]], phase: str) -> list[list[str]]:
    rows = []
    for b in items:
        src, dst = b["src"], b["dst"]
        queues = f"{src.get('queue') or '-'} &rarr; {dst.get('queue') or '-'}"
        aliases = b.get("aliases")
        note = "" if not aliases else f"aliases {escape(aliases if isinstance(aliases, str) else ', '.join(aliases))}"
        if src.get("layout") != dst.get("layout") and dst.get("layout"):
            note = (note + "; " if note else "") + "layout transition"
        rows.append([phase, res_link(b["resource"]) + escape(subresource(b.get("subresource"))),
                     _state(src), _state(dst), queues, note])
    return rows


def pass_summary_table(plan: Plan) -> str:
    rows = []
    for i, p in enumerate(plan["passes"]):
        waits = ", ".join(f"wait {w['queue']}&ge;{w['value']}" for w in p.get("waits") or [])
        signals = ", ".join(f"signal {s['queue']}={s['value']}" for s in p.get("signals") or [])
        rows.append([str(p.get("index", i)), pass_link(p["name"]), escape(p.get("kind") or "-"),
                     escape(p.get("queue") or "graphics"), escape(p.get("impl") or "probe"),
                     str(len(p.get("accesses") or [])), str(len(p.get("barriers") or [])),
                     str(len(p.get("releases") or [])), ", ".join(x for x in (waits, signals) if x)])
    return _table(("#", "pass", "kind", "queue", "impl", "accesses", "barriers", "releases", "semaphores"),
                  rows, "sortable")


def pass_details(plan: Plan) -> str:
    """Per pass: its accesses, then its waits, barriers (before), releases (after) and signals."""
    out = []
    for i, p in enumerate(plan["passes"]):
        name = p["name"]
        out.append(f'<section class="pass" id="{anchor("pass", name)}">')
        out.append(f'<h3>{p.get("index", i)}. {escape(name)} <span class="meta">{escape(p.get("kind") or "-")} on '
                   f'{escape(p.get("queue") or "graphics")}, {escape(p.get("impl") or "probe")}</span></h3>')
        accesses = [[res_link(a["resource"]) + escape(subresource(a.get("subresource"))), escape(a.get("usage") or "-"),
                     _fl(a.get("stages")), _fl(a.get("access")), escape(a.get("layout") or "-")]
                    for a in p.get("accesses") or []]
        out.append(_table(("resource", "usage", "stages", "access", "layout"), accesses, "acc"))
        sync = [[escape(f"wait {w['queue']} timeline >= {w['value']}"), "", "", _fl(w.get("stages")), "", ""]
                for w in p.get("waits") or []]
        sync += _barrier_rows(p.get("barriers") or [], "barrier before")
        sync += _barrier_rows(p.get("releases") or [], "release after")
        sync += [[escape(f"signal {s['queue']} timeline = {s['value']}"), "", _fl(s.get("stages")), "", "", ""]
                 for s in p.get("signals") or []]
        if sync:
            out.append(_table(("synchronization", "resource", "src stages / access / layout",
                               "dst stages / access / layout", "queues", "note"), sync, "sync"))
        else:
            out.append('<p class="none">No barriers, waits or signals.</p>')
        out.append("</section>")
    return "\n".join(out)


def culled_section(plan: Plan, timings: dict[str, Any] | None) -> str:
    culled = plan.get("culled") or []
    if not culled:
        return "<p>No pass was culled.</p>"
    per_resource = culled_resource_bytes(plan)
    rows = []
    for c in culled:
        names = c.get("resources")
        res = "(not listed)" if names is None else (", ".join(
            f'{escape(n)} ({escape(human_bytes(per_resource.get(n)))})' for n in names) or "(none)")
        ms = culled_ms(timings, c["pass"])
        rows.append([escape(c["pass"]), escape(c.get("reason") or "-"), res,
                     escape("-" if c.get("bytes") is None else bytes_exact(c["bytes"])),
                     "-" if ms is None else f"{ms:.3f}"])
    total = culled_bytes_total(plan)
    measured = [m for m in (culled_ms(timings, c["pass"]) for c in culled) if m is not None]
    parts = [] if total is None else [f"{escape(bytes_exact(total))} of memory (each resource counted once)"]
    if measured:
        parts.append(f"{sum(measured):.3f} ms of GPU time per frame (measured on "
                     f"{escape(str((timings or {}).get('device') or 'the timed device'))})")
    note = f"<p>Culling saved {' and '.join(parts)}.</p>" if parts else ""
    return _table(("culled pass", "reason", "resources only culled passes used", "bytes", "GPU ms saved"),
                  rows) + note


def resources_table(plan: Plan) -> str:
    rows = []
    for r in plan.get("resources") or []:
        shape = r.get("format") or r.get("kind") or "-"
        ext = r.get("extent")
        if ext:
            shape += f" {ext[0]}x{ext[1]}"
        for key in ("mips", "layers"):
            if (r.get(key) or 1) > 1:
                shape += f", {r[key]} {key}"
        users = [pass_link(p["name"]) for p in plan["passes"]
                 if any(a["resource"] == r["name"] for a in p.get("accesses") or [])]
        rows.append([f'<span id="{anchor("res", r["name"])}">{escape(r["name"])}</span>', escape(shape),
                     escape(bytes_exact(r.get("bytes"))), escape(r.get("lifetime") or "-"),
                     escape(lifetime_cell(plan, r)), escape(str(r.get("heap", "-"))), escape(str(r.get("offset", "-"))),
                     ", ".join(users)])
    return _table(("resource", "shape", "bytes", "lifetime", "passes", "heap", "offset", "used by"), rows)
