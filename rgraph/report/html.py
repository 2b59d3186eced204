"""The ``--html`` view: one self-contained page (no external links) with every view.

The timeline PNG is embedded as base64; the pass graph as inline SVG when graphviz is there.
"""

from __future__ import annotations

import base64
import html
import tempfile
from pathlib import Path
from typing import Any

from rgraph.report import barriers, memory, summary
from rgraph.report.dot import dot_available, dot_to_svg, plan_to_dot
from rgraph.report.table import TableData
from rgraph.report.timeline import write_timeline_png

Plan = dict[str, Any]

STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em; color: #222; max-width: 1400px; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0 1em 0; }
th, td { border: 1px solid #ddd; padding: 3px 8px; text-align: left; vertical-align: top; }
th { background: #f3f3f3; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
pre { background: #f7f7f7; padding: 0.8em; font-size: 0.8em; overflow-x: auto; }
img, svg { max-width: 100%; height: auto; }
"""


def table_html(data: TableData) -> str:
    """A titled HTML table (or the ``empty`` note)."""
    out = [f"<h3>{html.escape(data.title)}</h3>"]
    if not data.rows:
        out.append(f"<p>{html.escape(data.empty)}</p>")
        return "\n".join(out)
    out.append("<table>")
    out.append("<tr>" + "".join(f"<th>{html.escape(c)}</th>" for c in data.columns) + "</tr>")
    for row in data.rows:
        cells = []
        for col, cell in zip(data.columns, row, strict=True):
            cls = ' class="num"' if col in data.right else ""
            cells.append(f"<td{cls}>{html.escape(cell)}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _pre(lines: list[str]) -> str:
    return "<pre>" + html.escape("\n".join(lines)) + "</pre>"


def timeline_png_bytes(plan: Plan) -> bytes:
    """The timeline PNG, drawn into a temporary file."""
    with tempfile.TemporaryDirectory(prefix="rgraph-html-") as tmp:
        path = Path(tmp) / "timeline.png"
        write_timeline_png(plan, path)
        return path.read_bytes()


def plan_html(plan: Plan, with_svg: bool | None = None) -> str:
    """The page; ``with_svg`` defaults to whether graphviz is installed."""
    if with_svg is None:
        with_svg = dot_available()
    title = f"rgraph plan: {plan.get('graph') or '?'}"
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title>",
        f"<style>{STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        '<h2 id="summary">Summary</h2>',
        _pre(summary.header_lines(plan)),
        _pre(summary.stats_lines(plan)),
        '<h2 id="schedule">Schedule</h2>',
        table_html(summary.schedule_table(plan)),
        table_html(summary.culled_table(plan)),
        table_html(summary.dropped_table(plan)),
        '<h2 id="barriers">Barriers</h2>',
        _pre(barriers.barrier_lines(plan) + ["", barriers.barrier_totals(plan)]),
        '<h2 id="memory">Memory</h2>',
        table_html(memory.resources_table(plan)),
        table_html(memory.heaps_table(plan)),
        _pre(memory.class_lines(plan)),
        table_html(memory.culling_table(plan)),
    ]
    total = memory.culling_total_line(plan)
    if total:
        parts.append(f"<p>{html.escape(total)}</p>")
    png = base64.b64encode(timeline_png_bytes(plan)).decode("ascii")
    parts += [
        '<h2 id="timeline">Memory timeline</h2>',
        f'<img alt="memory timeline" src="data:image/png;base64,{png}">',
        '<h2 id="graph">Pass graph</h2>',
    ]
    dot_text = plan_to_dot(plan)
    if with_svg:
        svg = dot_to_svg(dot_text)
        parts.append(svg[svg.find("<svg"):] if "<svg" in svg else svg)
    else:
        parts.append("<p>graphviz is not installed; the DOT text:</p>")
        parts.append("<pre>" + html.escape(dot_text) + "</pre>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
