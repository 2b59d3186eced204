"""The ``--html`` view: one self-contained interactive page (no network, no external files).

Sections: summary, GPU timeline per queue (from ``--timings`` when given), the pass graph
(inline SVG from graphviz, or the DOT text), the memory timeline (inline SVG, hover for
details), every pass with its accesses and barriers (anchors ``#pass-NAME``), culled passes
with their reasons and savings, resources (``#res-NAME``) and heaps.
"""

from __future__ import annotations

import html
import re
from typing import Any

from rgraph.report import html_passes, memory, summary
from rgraph.report.dot import dot_available, dot_to_svg, plan_to_dot
from rgraph.report.html_svg import gpu_svg, lifetimes_svg, memory_svg
from rgraph.report.table import TableData

Plan = dict[str, Any]

STYLE = """
:root { --line: #d8dce3; --head: #f3f5f8; --ink: #1f2328; --mute: #667085; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0; color: var(--ink); }
header { position: sticky; top: 0; background: #fff; border-bottom: 1px solid var(--line); padding: 8px 24px;
         z-index: 2; display: flex; gap: 18px; align-items: baseline; flex-wrap: wrap; }
header h1 { font-size: 18px; margin: 0 12px 0 0; }
header a { color: #2456a6; text-decoration: none; }
main { padding: 0 24px 40px 24px; max-width: 1200px; }
h2 { font-size: 17px; margin: 28px 0 8px 0; padding-top: 6px; border-bottom: 1px solid var(--line); }
h3 { font-size: 14px; margin: 18px 0 6px 0; }
.meta, .none, .note { color: var(--mute); font-weight: normal; }
table { border-collapse: collapse; font-size: 12.5px; margin: 4px 0 12px 0; max-width: 100%; }
table.acc td, table.sync td { overflow-wrap: anywhere; }
th, td { border: 1px solid var(--line); padding: 3px 7px; text-align: left; vertical-align: top; }
th { background: var(--head); position: sticky; top: 44px; }
td .acc { color: #8a4b08; } td .lay { color: #2b6a3f; }
pre { background: #f7f8fa; padding: 8px; font-size: 12px; white-space: pre-wrap; word-break: break-all; }
dl.kv { display: grid; grid-template-columns: max-content 1fr; gap: 2px 14px; margin: 6px 0; }
dl.kv dt { color: var(--mute); } dl.kv dd { margin: 0; }
.chart { max-width: 100%; height: auto; font-family: system-ui, sans-serif; }
.chart .lbl { font-size: 11px; fill: #fff; pointer-events: none; }
.chart .axis { font-size: 11px; fill: #444; } .chart .panel { font-size: 12px; font-weight: 600; fill: #222; }
.chart .frame { fill: #fafbfc; stroke: #ccd; } .chart .grid { stroke: #e6e8ec; }
.chart .heap { stroke: #000; stroke-dasharray: 2 3; }
.chart .live { fill: none; stroke: #666; stroke-dasharray: 1 2; }
.chart .res, .chart .pass { stroke: #222; stroke-width: 0.6; opacity: 0.88; cursor: pointer; }
.chart .held { stroke-dasharray: 4 2; }
.chart .res:hover, .chart .pass:hover, .chart .hi { opacity: 1; stroke-width: 2.2; }
.chart .wait { stroke: #7a3db8; stroke-width: 1.5; }
.graph svg { max-width: 100%; height: auto; }
section.pass { border-left: 3px solid var(--line); padding-left: 10px; margin: 10px 0; }
section.pass:target { border-left-color: #2456a6; background: #f5f8ff; }
#tip { position: fixed; pointer-events: none; background: #1f2328; color: #fff; padding: 5px 8px;
       border-radius: 4px; font-size: 12px; max-width: 480px; display: none; z-index: 5; }
#filter { margin: 4px 0 8px 0; padding: 3px 6px; width: 260px; }
"""

SCRIPT = """
(function () {
  var tip = document.getElementById('tip');
  document.addEventListener('mousemove', function (e) {
    var t = e.target.closest ? e.target.closest('[data-tip]') : null;
    if (!t) { tip.style.display = 'none'; return; }
    tip.textContent = t.getAttribute('data-tip');
    tip.style.display = 'block';
    tip.style.left = Math.min(e.clientX + 14, window.innerWidth - 500) + 'px';
    tip.style.top = (e.clientY + 14) + 'px';
  });
  document.addEventListener('click', function (e) {
    var t = e.target.closest ? e.target.closest('[data-pass],[data-res]') : null;
    if (!t) return;
    var pass = t.getAttribute('data-pass');
    if (pass) { location.hash = 'pass-' + pass; return; }
    location.hash = 'res-' + t.getAttribute('data-res');
  });
  var filter = document.getElementById('filter');
  if (filter) filter.addEventListener('input', function () {
    var q = filter.value.toLowerCase();
    document.querySelectorAll('section.pass').forEach(function (s) {
      s.style.display = s.textContent.toLowerCase().indexOf(q) >= 0 ? '' : 'none';
    });
  });
})();
"""

SECTIONS = (("summary", "Summary"), ("gpu", "GPU timeline"), ("graph", "Pass graph"),
            ("memory", "Memory"), ("passes", "Passes"), ("culled", "Culled passes"),
            ("resources", "Resources"))


def table_html(data: TableData, heading: bool = True) -> str:
    """A table (with its title as an h3 when ``heading``), or the ``empty`` note."""
    out = [f"<h3>{html.escape(data.title)}</h3>"] if heading else []
    if not data.rows:
        out.append(f'<p class="none">{html.escape(data.empty)}</p>')
        return "\n".join(out)
    out.append("<table><thead><tr>" + "".join(f"<th>{html.escape(c)}</th>" for c in data.columns) + "</tr></thead>")
    out.append("<tbody>")
    for row in data.rows:
        out.append("<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in row) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def _kv(lines: list[str]) -> str:
    """``key  value`` lines as a definition list."""
    items = []
    for line in lines:
        match = re.match(r"^(.*?\S)\s{2,}(.*)$", line)
        key, value = match.groups() if match else (line.partition(" ")[0], line.partition(" ")[2])
        items.append(f"<dt>{html.escape(key)}</dt><dd>{html.escape(value.strip())}</dd>")
    return '<dl class="kv">' + "".join(items) + "</dl>"


def _gpu_section(plan: Plan, timings: dict | None) -> str:
    if timings:
        frames = timings.get("frames")
        total = timings.get("total_ms")
        where = (f"measured on {html.escape(str(timings.get('device') or '?'))}"
                 f"{f' over {frames} frames' if frames else ''}"
                 f"{f'; measured frame total {total:.3f} ms' if isinstance(total, (int, float)) else ''}")
        if timings.get("intervals"):
            note = (f"Each pass's median start and end within the frame from GPU timestamps, {where}. Arrows are "
                    "semaphore waits; overlap between lanes is async work running beside graphics.")
        else:
            note = (f"Bar lengths are the per-pass GPU medians {where}. This timings file has no timestamps "
                    "per pass, so start times are derived: each pass starts after the previous pass on its "
                    "queue and after the semaphore signals it waits for (arrows).")
    else:
        note = ("No timings given: each pass is drawn one slot long to show the queue structure. For measured "
                "times: <code>rgraph run G --timings t.json</code>, then <code>rgraph inspect G --timings t.json "
                "--html report.html</code>.")
    return f'<p class="note">{note}</p>' + gpu_svg(plan, timings)


def _graph_section(plan: Plan, with_svg: bool) -> str:
    dot_text = plan_to_dot(plan)
    if with_svg:
        svg = dot_to_svg(dot_text)
        svg = svg[svg.find("<svg"):] if "<svg" in svg else svg
        return ('<p class="note">RAW edges solid, WAR dashed, WAW dotted; semaphore waits bold purple; culled '
                f'passes dashed grey.</p><div class="graph">{svg}</div>')
    return ("<p>graphviz is not installed (scripts/setup.sh installs it); the DOT text:</p>"
            f"<pre>{html.escape(dot_text)}</pre>")


def plan_html(plan: Plan, with_svg: bool | None = None, timings: dict | None = None) -> str:
    """The page; ``with_svg`` defaults to whether graphviz is installed; ``timings`` is a
    ``rgraph run --timings`` file of the same plan (size checked by the caller)."""
    if with_svg is None:
        with_svg = dot_available()
    title = f"rgraph plan: {plan.get('graph') or '?'}"
    nav = "".join(f'<a href="#{key}">{name}</a>' for key, name in SECTIONS)
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title>",
        f"<style>{STYLE}</style></head><body>",
        f"<header><h1>{html.escape(title)}</h1>{nav}</header><main>",
        '<h2 id="summary">Summary</h2>',
        _kv(summary.header_lines(plan)),
        _kv(summary.stats_lines(plan)),
        table_html(summary.dropped_table(plan)),
        '<h2 id="gpu">GPU timeline per queue</h2>',
        _gpu_section(plan, timings),
        '<h2 id="graph">Pass graph</h2>',
        _graph_section(plan, with_svg),
        '<h2 id="memory">Memory</h2>',
        '<p class="note">Offset within the heaps of each memory class (up) against the executed pass (across); '
        "dashed outlines are held all frame (persistent, imported, output); the dotted line is the live bytes. "
        "Hover a block for its size, heap, offset and passes; click it for the resource.</p>",
        "<h3>Placement</h3>",
        memory_svg(plan),
        "<h3>Lifetimes</h3>",
        '<p class="note">One row per resource, coloured by heap: resources whose rows do not overlap in time '
        "may share memory.</p>",
        lifetimes_svg(plan),
        table_html(memory.heaps_table(plan)),
        '<h2 id="passes">Passes</h2>',
        html_passes.pass_summary_table(plan),
        '<input id="filter" type="search" placeholder="filter passes (name, resource, layout...)">',
        html_passes.pass_details(plan),
        '<h2 id="culled">Culled passes</h2>',
        html_passes.culled_section(plan, timings),
        '<h2 id="resources">Resources</h2>',
        html_passes.resources_table(plan),
        '</main><div id="tip"></div>',
        f"<script>{SCRIPT}</script>",
        "</body></html>",
    ]
    return "\n".join(parts) + "\n"
