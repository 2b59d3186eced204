"""The ``--dot`` view: the pass graph as deterministic Graphviz DOT text, optionally as SVG.

Nodes are the executed passes in order (kind, queue, impl), and culled passes dashed grey
with their reason as tooltip. Edges: RAW solid, WAR dashed, WAW dotted, each labelled with
its resources; semaphore signal -> wait edges bold.
"""

from __future__ import annotations

import shutil
import subprocess
from typing import Any

from rgraph.report.deps import dependency_edges, semaphore_edges

Plan = dict[str, Any]

QUEUE_FILL = {"graphics": "#dbe8f7", "compute": "#fbe8c8", "transfer": "#e3f1dc"}
EDGE_STYLE = {
    "RAW": 'style=solid, color="#303030"',
    "WAR": 'style=dashed, color="#2a6fb0"',
    "WAW": 'style=dotted, color="#b03a2a"',
}


def quote(text: str) -> str:
    """A DOT double-quoted string."""
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{escaped}"'


def _node_id(index: int) -> str:
    return f"p{index}"


def plan_to_dot(plan: Plan) -> str:
    """The DOT text; the same plan gives the same bytes."""
    passes = plan["passes"]
    lines = [
        f"digraph {quote(plan.get('graph') or 'plan')} {{",
        "  rankdir=TB;",
        '  graph [fontname="Helvetica", fontsize=11];',
        '  node [shape=box, style="rounded,filled", fontname="Helvetica", fontsize=10];',
        '  edge [fontname="Helvetica", fontsize=9];',
    ]
    for i, p in enumerate(passes):
        queue = p.get("queue") or "graphics"
        label = f"{i}: {p['name']}\n{p.get('kind') or '?'} on {queue}\n{p.get('impl') or 'probe'}"
        fill = QUEUE_FILL.get(queue, "#eeeeee")
        lines.append(f"  {_node_id(i)} [label={quote(label)}, fillcolor={quote(fill)}];")
    for j, c in enumerate(plan.get("culled") or []):
        reason = c.get("reason") or "culled"
        lines.append(
            f"  c{j} [label={quote(c['pass'] + chr(10) + 'culled')}, tooltip={quote(reason)}, "
            'style="rounded,dashed", color="#999999", fontcolor="#999999"];'
        )
    for e in dependency_edges(plan):
        label = f"{e.kind} {', '.join(e.resources)}"
        lines.append(
            f"  {_node_id(e.src)} -> {_node_id(e.dst)} [label={quote(label)}, {EDGE_STYLE[e.kind]}];"
        )
    for s in semaphore_edges(plan):
        label = f"{s.queue} >= {s.value}"
        lines.append(
            f"  {_node_id(s.src)} -> {_node_id(s.dst)} [label={quote(label)}, style=bold, penwidth=2.5, "
            'color="#7a3db8", fontcolor="#7a3db8"];'
        )
    lines.append("}")
    return "\n".join(lines) + "\n"


def dot_available() -> bool:
    """Whether graphviz's ``dot`` is on PATH."""
    return shutil.which("dot") is not None


RENDERED_SUFFIXES = ("svg", "pdf", "png")
TEXT_SUFFIXES = ("dot", "gv")


def dot_render(dot_text: str, fmt: str) -> bytes:
    """``dot -T<fmt>`` output; raises ``RuntimeError`` when dot fails or is missing."""
    exe = shutil.which("dot")
    if exe is None:
        raise RuntimeError("graphviz 'dot' is not installed")
    proc = subprocess.run([exe, f"-T{fmt}"], input=dot_text.encode(), capture_output=True, timeout=60)
    if proc.returncode != 0:
        raise RuntimeError(f"dot -T{fmt} failed ({proc.returncode}): {proc.stderr.decode(errors='replace').strip()}")
    return proc.stdout


def dot_to_svg(dot_text: str) -> str:
    """SVG rendered by ``dot -Tsvg``; raises ``RuntimeError`` when dot fails or is missing."""
    return dot_render(dot_text, "svg").decode("utf-8")
