"""Inline SVG pictures of the HTML report: the memory timeline and the GPU timeline per queue.

Every shape carries a ``data-tip`` (the page's script shows it on hover) and an SVG
``<title>`` (the browser's own tooltip), so the details are there without any network or
library. Labels are drawn only where they fit; the rest is in the tooltip.
"""

from __future__ import annotations

from html import escape
from typing import Any

from rgraph.report.fmt import MIB, human_bytes
from rgraph.report.timeline import class_layout, live_bytes, placed_blocks

Plan = dict[str, Any]

PALETTE = ("#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#76b7b2", "#edc948", "#b07aa1", "#ff9da7",
           "#9c755f", "#bab0ac")
QUEUE_COLOR = {"graphics": "#4e79a7", "compute": "#f28e2b", "transfer": "#59a14f"}
WIDTH = 1100
LEFT = 170  # room for the axis labels
RIGHT = 20
CHAR_W = 6.2  # px per character at font-size 11


def _attr(text: str) -> str:
    return escape(text, quote=True)


def _shape(tag: str, tip: str, **attrs: Any) -> str:
    parts = " ".join(f'{k.rstrip("_").replace("_", "-")}="{_attr(str(v))}"' for k, v in attrs.items())
    return f'<{tag} {parts} data-tip="{_attr(tip)}"><title>{escape(tip)}</title></{tag}>'


def _label(x: float, y: float, text: str, width: float, height: float, anchor: str = "middle") -> str:
    """A label centred at (x, y), or nothing when ``text`` does not fit ``width`` x ``height``."""
    if height < 12 or len(text) * CHAR_W > width - 4:
        return ""
    return (f'<text x="{x:.1f}" y="{y + 4:.1f}" text-anchor="{anchor}" class="lbl">{escape(text)}</text>')


def _unit(top: int) -> tuple[int, str]:
    return (MIB, "MiB") if top >= MIB else (1024, "KiB") if top >= 1024 else (1, "B")


def _with_pass_axis(out: list[str], passes: list[dict], col: float, y: float, label: str) -> str:
    """The chart ``out`` closed by pass names across at ``y`` (rotated so they never overlap,
    each a link to its pass) in an ``<svg>`` tall enough for the longest name."""
    for i, p in enumerate(passes):
        x = LEFT + (i + 0.5) * col
        out.append(f'<text transform="translate({x:.1f},{y:.1f}) rotate(-35)" text-anchor="end" class="axis">'
                   f'<a href="#pass-{_attr(p["name"])}">{i} {escape(p["name"])}</a></text>')
    longest = max((len(p["name"]) for p in passes), default=4) + 3
    total_h = int(y + longest * CHAR_W * 0.6) + 30
    return (f'<svg class="chart" viewBox="0 0 {WIDTH} {total_h}" width="{WIDTH}" height="{total_h}" role="img" '
            f'aria-label="{label}">' + "".join(out) + "</svg>")


def memory_svg(plan: Plan) -> str:
    """Offset (up) against pass index (across), one panel per memory class; hover for details."""
    passes = plan["passes"]
    n = max(len(passes), 1)
    blocks = placed_blocks(plan)
    if not blocks:
        return "<p>No placed resources.</p>"
    layout = class_layout(plan) or {"-": [(b, 0, 0) for b in sorted({b.heap for b in blocks})]}
    heap_base = {heap: base for column in layout.values() for heap, base, _ in column}
    col = (WIDTH - LEFT - RIGHT) / n
    out: list[str] = []
    y0 = 24
    for cls, column in layout.items():
        heaps = {heap for heap, _, _ in column}
        members = [b for b in blocks if b.heap in heaps]
        total = max([base + size for _, base, size in column] + [1])
        top = max([total, 1] + [heap_base[b.heap] + b.offset + b.aligned_size for b in members])
        height = 300 if top >= total and len(members) > 3 else 160
        scale, unit = _unit(top)

        def ypos(value: float, _top=top, _y0=y0, _h=height) -> float:
            return _y0 + _h - value / _top * _h

        out.append(f'<text x="{LEFT}" y="{y0 - 8:.0f}" class="panel">{escape(cls)}: '
                   f'{len(column)} heap{"s" if len(column) != 1 else ""}, {escape(human_bytes(total))}</text>')
        out.append(f'<rect x="{LEFT}" y="{y0 + 4}" width="{WIDTH - LEFT - RIGHT}" height="{height - 4}" class="frame"/>')
        for tick in range(5):
            value = top * tick / 4
            y = ypos(value)
            out.append(f'<line x1="{LEFT - 4}" x2="{WIDTH - RIGHT}" y1="{y:.1f}" y2="{y:.1f}" class="grid"/>')
            out.append(f'<text x="{LEFT - 8}" y="{y + 4:.1f}" text-anchor="end" class="axis">'
                       f'{value / scale:.1f} {unit}</text>')
        for heap, base, size in column:
            y = ypos(base + size)
            out.append(_shape("line", f"heap {heap}: {human_bytes(size)} ({size} B) at {base} in {cls}",
                              x1=LEFT, x2=WIDTH - RIGHT, y1=f"{y:.1f}", y2=f"{y:.1f}", class_="heap"))
        for i, b in enumerate(members):
            x = LEFT + (b.start + 0.05) * col
            w = (b.end - b.start + 0.9) * col
            y_top = ypos(heap_base[b.heap] + b.offset + b.aligned_size)
            h = max(ypos(heap_base[b.heap] + b.offset) - y_top, 1.5)
            kind = "transient (aliasable)" if b.aliasable else "held all frame (persistent, imported or output)"
            tip = (f"{b.name}: {human_bytes(b.size)} ({b.size} B, aligned {b.aligned_size} B), heap {b.heap} "
                   f"offset {b.offset}, passes {b.start}..{b.end} ({passes[b.start]['name']}..{passes[b.end]['name']}), "
                   f"{kind}")
            out.append(_shape("rect", tip, x=f"{x:.1f}", y=f"{y_top:.1f}", width=f"{w:.1f}", height=f"{h:.1f}",
                              fill=PALETTE[i % len(PALETTE)], class_="res" + ("" if b.aliasable else " held"),
                              data_res=b.name))
            out.append(_label(x + w / 2, y_top + h / 2, b.name, w, h))
        live = live_bytes(members, len(passes))
        points = " ".join(f"{LEFT + (t + 0.5) * col:.1f},{ypos(v):.1f}" for t, v in enumerate(live))
        out.append(_shape("polyline", f"live bytes per pass; peak {human_bytes(max(live, default=0))}",
                          points=points, class_="live"))
        y0 += height + 40
    return _with_pass_axis(out, passes, col, y0 - 20, "memory timeline")


def lifetimes_svg(plan: Plan) -> str:
    """One row per placed resource (by first use): its live passes, coloured by heap; hover for details."""
    passes = plan["passes"]
    n = max(len(passes), 1)
    blocks = sorted(placed_blocks(plan), key=lambda b: (b.start, b.end, b.name))
    if not blocks:
        return ""
    heaps = sorted({b.heap for b in blocks})
    col = (WIDTH - LEFT - RIGHT) / n
    row_h, top = 18, 6
    out = []
    for i in range(len(passes) + 1):
        x = LEFT + i * col
        out.append(f'<line x1="{x:.1f}" x2="{x:.1f}" y1="{top}" y2="{top + row_h * len(blocks)}" class="grid"/>')
    for k, b in enumerate(blocks):
        y = top + k * row_h
        x, w = LEFT + (b.start + 0.05) * col, (b.end - b.start + 0.9) * col
        label = f"{b.name} ({human_bytes(b.size)})"
        out.append(f'<text x="{LEFT - 8}" y="{y + 13}" text-anchor="end" class="axis">'
                   f'<a href="#res-{_attr(b.name)}">{escape(label)}</a></text>')
        tip = (f"{b.name}: {human_bytes(b.size)}, heap {b.heap} offset {b.offset}, live in passes {b.start}..{b.end} "
               f"({passes[b.start]['name']}..{passes[b.end]['name']})")
        out.append(_shape("rect", tip, x=f"{x:.1f}", y=f"{y + 2}", width=f"{w:.1f}", height=row_h - 4,
                          fill=PALETTE[heaps.index(b.heap) % len(PALETTE)], class_="res" + ("" if b.aliasable else " held"),
                          data_res=b.name))
    return _with_pass_axis(out, passes, col, top + row_h * len(blocks) + 12, "resource lifetimes")


def gpu_layout(plan: Plan, timings: dict[str, Any] | None) -> list[dict[str, Any]]:
    """Per executed pass: queue, start and end in ms.

    From the GPU timestamps of the timings file (``intervals``: median start/end of each pass
    within the frame) when it has them for every pass. Otherwise laid out from the per-pass
    medians: a pass starts when the previous pass on its queue has ended and every semaphore it waits
    for has been signalled (the signalling pass has ended). Without timings each pass is one
    unit long. The start times are derived; only the durations are measured.
    """
    measured = (timings or {}).get("passes") or {}
    intervals = (timings or {}).get("intervals") or {}
    if intervals and all(p["name"] in intervals for p in plan["passes"]):  # GPU timestamps (rgraph run)
        return [{"name": p["name"], "index": p.get("index"), "queue": p.get("queue") or "graphics",
                 "start": intervals[p["name"]]["start_ms"], "end": intervals[p["name"]]["end_ms"],
                 "ms": measured.get(p["name"]), "waits": p.get("waits") or [], "timestamps": True}
                for p in plan["passes"]]
    queue_end: dict[str, float] = {}
    signalled: dict[tuple[str, int], float] = {}
    rows = []
    for p in plan["passes"]:
        queue = p.get("queue") or "graphics"
        ms = measured.get(p["name"]) if timings else 1.0
        duration = float(ms) if isinstance(ms, (int, float)) else 0.0
        start = max([queue_end.get(queue, 0.0)] + [signalled.get((w["queue"], w["value"]), 0.0)
                                                    for w in p.get("waits") or []])
        end = start + duration
        queue_end[queue] = end
        for s in p.get("signals") or []:
            signalled[(s["queue"], s["value"])] = end
        rows.append({"name": p["name"], "index": p.get("index"), "queue": queue, "start": start, "end": end,
                     "ms": ms if timings else None, "waits": p.get("waits") or []})
    return rows


def gpu_svg(plan: Plan, timings: dict[str, Any] | None) -> str:
    """One lane per queue, a bar per pass (hover: measured ms, derived start), semaphore waits as arrows."""
    rows = gpu_layout(plan, timings)
    if not rows:
        return "<p>No passes execute.</p>"
    queues = [q for q in plan.get("queues") or [] if any(r["queue"] == q for r in rows)]
    queues += sorted({r["queue"] for r in rows} - set(queues))
    span = max(r["end"] for r in rows) or 1.0
    lane_h, top = 46, 26
    scale = (WIDTH - LEFT - RIGHT) / span
    out = []
    unit = "ms" if timings else "slot"
    for tick in range(6):
        t = span * tick / 5
        x = LEFT + t * scale
        out.append(f'<line x1="{x:.1f}" x2="{x:.1f}" y1="{top - 6}" y2="{top + lane_h * len(queues)}" class="grid"/>')
        anchor = "start" if tick == 0 else "end" if tick == 5 else "middle"
        out.append(f'<text x="{x:.1f}" y="{top - 10}" text-anchor="{anchor}" class="axis">{t:.2f} {unit}</text>')
    lane = {q: i for i, q in enumerate(queues)}
    for q, i in lane.items():
        y = top + i * lane_h
        out.append(f'<text x="{LEFT - 8}" y="{y + lane_h / 2 + 4:.1f}" text-anchor="end" class="panel">{escape(q)}</text>')
        out.append(f'<rect x="{LEFT}" y="{y + 2}" width="{WIDTH - LEFT - RIGHT}" height="{lane_h - 4}" class="frame"/>')
    ends = {}
    for r in rows:
        y = top + lane[r["queue"]] * lane_h + 6
        x, w = LEFT + r["start"] * scale, max((r["end"] - r["start"]) * scale, 1.5)
        timing = f"{r['ms']:.3f} ms measured" if isinstance(r["ms"], (int, float)) else (
            "not in the timings file" if timings else "untimed")
        how = "GPU timestamp" if r.get("timestamps") else "derived"
        tip = f"{r['index']} {r['name']} on {r['queue']}: {timing}; starts at {r['start']:.3f} {unit} ({how})"
        out.append(_shape("rect", tip, x=f"{x:.1f}", y=f"{y:.1f}", width=f"{w:.1f}", height=lane_h - 12,
                          fill=QUEUE_COLOR.get(r["queue"], "#999999"), class_="pass", data_pass=r["name"]))
        out.append(_label(x + w / 2, y + (lane_h - 12) / 2, r["name"], w, lane_h - 12))
        ends[(r["queue"], r["name"])] = (x + w, y)
    signal_pos = {}
    for r, p in zip(rows, plan["passes"], strict=True):
        for s in p.get("signals") or []:
            signal_pos[(s["queue"], s["value"])] = ends[(r["queue"], r["name"])]
    for r in rows:
        for wt in r["waits"]:
            src = signal_pos.get((wt["queue"], wt["value"]))
            if src is None:
                continue
            x2 = LEFT + r["start"] * scale
            y2 = top + lane[r["queue"]] * lane_h + 6
            tip = f"{r['name']} waits for {wt['queue']} timeline >= {wt['value']}"
            out.append(_shape("line", tip, x1=f"{src[0]:.1f}", y1=f"{src[1] + 17:.1f}", x2=f"{x2:.1f}",
                              y2=f"{y2 + 17:.1f}", class_="wait", marker_end="url(#arrow)"))
    height = top + lane_h * len(queues) + 10
    defs = ('<defs><marker id="arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" '
            'orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="#7a3db8"/></marker></defs>')
    return (f'<svg class="chart" viewBox="0 0 {WIDTH} {height}" width="{WIDTH}" height="{height}" role="img" '
            f'aria-label="GPU timeline per queue">' + defs + "".join(out) + "</svg>")
