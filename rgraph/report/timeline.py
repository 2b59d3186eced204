"""The ``--timeline`` view: the plan's memory placement drawn as PNG, SVG or PDF (by suffix).

Pass index runs across, offset up (a panel per memory class, its heaps stacked in id
order); one rectangle per placed resource. ``rgraph.memory.timeline.draw_timeline`` can
draw the transient part instead, from blocks converted out of the plan.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rgraph.report.fmt import MIB, align_up, human_bytes, percent

Plan = dict[str, Any]


@dataclass(frozen=True)
class PlacedBlock:
    """A placed resource over an inclusive range of pass indices."""

    name: str
    start: int
    end: int
    size: int
    alignment: int
    memory_class: str
    heap: int
    offset: int
    aliasable: bool  # transient resources alias; persistent/imported/output ones hold memory all frame

    @property
    def aligned_size(self) -> int:
        return align_up(self.size, self.alignment)


def placed_blocks(plan: Plan) -> list[PlacedBlock]:
    """Every resource that has a heap, an offset and a pass, in plan (name) order."""
    last_pass = max(len(plan["passes"]) - 1, 0)
    blocks = []
    for r in plan.get("resources") or []:
        if r.get("heap") is None or r.get("offset") is None or r.get("first") is None:
            continue
        transient = (r.get("lifetime") or "transient") == "transient"
        start, end = (r["first"], r["last"]) if transient else (0, last_pass)
        blocks.append(
            PlacedBlock(
                name=r["name"],
                start=start,
                end=end,
                size=r.get("bytes") or 0,
                alignment=r.get("alignment") or 1,
                memory_class=r.get("memory_class") or "-",
                heap=r["heap"],
                offset=r["offset"],
                aliasable=transient,
            )
        )
    return blocks


def live_bytes(blocks: list[PlacedBlock], n_passes: int) -> list[int]:
    """Aligned bytes alive at each pass index."""
    live = [0] * max(n_passes, 1)
    for b in blocks:
        for t in range(b.start, min(b.end, len(live) - 1) + 1):
            live[t] += b.aligned_size
    return live


def timeline_title(plan: Plan) -> str:
    """Graph, policy, peak, lower bound and saving against unaliased memory."""
    stats = plan.get("stats") or {}
    peak, lower, unaliased = stats.get("peak_bytes"), stats.get("lower_bound_bytes"), stats.get("unaliased_bytes")
    parts = [f"{plan.get('graph') or 'plan'}: {stats.get('policy') or '?'} placement"]
    if peak is not None:
        parts.append(f"peak {human_bytes(peak)}")
    if lower is not None:
        parts.append(f"lower bound {human_bytes(lower)}")
    if peak is not None and unaliased:
        parts.append(f"saving {percent(unaliased - peak, unaliased)} of {human_bytes(unaliased)}")
    return ", ".join(parts)


def write_timeline_png(plan: Plan, path: str | Path, title: str | None = None, drawer: str = "report") -> str:
    """Draw the plan's placement into ``path``; returns the drawer used (``report`` or ``memory``).

    ``report`` (default) draws every placed resource, a panel per memory class, pass names
    across. ``memory`` hands the transient (aliased) blocks to the placement library's
    ``draw_timeline``, the picture ``rgraph place`` draws; it falls back to ``report`` when
    that library is absent. Non-transient resources each own a heap, and ``draw_timeline``
    draws its class's lower bound in every heap panel, so they are left out there.
    """
    if drawer not in ("report", "memory"):
        raise ValueError(f"unknown timeline drawer {drawer!r}")
    if drawer == "memory":
        try:
            from rgraph.memory.timeline import draw_timeline
        except ImportError:
            draw_timeline = None
        if draw_timeline is not None:
            blocks, placement = to_memory_model(plan)
            draw_timeline(blocks, placement, str(path), title or str(plan.get("graph") or "plan"))
            return "memory"
    draw_plan_timeline(plan, path, title or timeline_title(plan))
    return "report"


def to_memory_model(plan: Plan) -> tuple[list[Any], Any]:
    """The plan's transient resources as ``rgraph.memory.model`` blocks and placement."""
    from rgraph.memory.model import Block, Heap, Placement, PlacementStats

    placed = [b for b in placed_blocks(plan) if b.aliasable]
    blocks = [Block(b.name, b.start, b.end, b.size, b.alignment, b.memory_class) for b in placed]
    used = {b.heap for b in placed}
    heaps = [
        Heap(h["id"], h["bytes"], h.get("memory_class") or "-", h.get("alignment") or 1)
        for h in plan.get("heaps") or []
        if h["id"] in used
    ]
    peak = sum(h.bytes for h in heaps)
    unaliased = sum(b.aligned_size for b in placed)
    lower = sum(max(live_bytes([b for b in placed if b.memory_class == cls], len(plan["passes"])), default=0)
                for cls in sorted({b.memory_class for b in placed}))
    placement = Placement(
        offsets={b.name: (b.heap, b.offset) for b in placed},
        heaps=heaps,
        stats=PlacementStats(
            policy=(plan.get("stats") or {}).get("policy") or "?",
            peak_bytes=peak,
            lower_bound_bytes=lower,
            unaliased_bytes=unaliased,
            allocations=len(heaps),
            seconds=0.0,
        ),
    )
    return blocks, placement


def class_layout(plan: Plan) -> dict[str, list[tuple[int, int, int]]]:
    """Per memory class (sorted), its heaps as (heap id, base, bytes), stacked in id order."""
    layout: dict[str, list[tuple[int, int, int]]] = {}
    for h in sorted(plan.get("heaps") or [], key=lambda h: h["id"]):
        column = layout.setdefault(h.get("memory_class") or "-", [])
        base = column[-1][1] + column[-1][2] if column else 0
        column.append((h["id"], base, h["bytes"]))
    return dict(sorted(layout.items()))


def draw_plan_timeline(plan: Plan, path: str | Path, title: str) -> None:
    """This module's own drawing: one panel per memory class, its heaps stacked bottom-up."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    passes = plan["passes"]
    n = max(len(passes), 1)
    blocks = placed_blocks(plan)
    layout = class_layout(plan) or {"-": [(b, 0, 0) for b in sorted({b.heap for b in blocks})]}
    heap_base = {heap: base for column in layout.values() for heap, base, _ in column}
    totals = {cls: max([base + size for _, base, size in column] + [1]) for cls, column in layout.items()}
    biggest = max(totals.values())
    ratios = [min(max((totals[cls] / biggest) ** 0.5, 0.35), 1.0) for cls in layout]
    fig = Figure(figsize=(max(9.0, 1.1 * n + 4), 2.0 + 3.6 * sum(ratios)), dpi=100)
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(layout), 1, sharex=True, squeeze=False, height_ratios=ratios)[:, 0]
    palette = [
        "#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#76b7b2", "#edc948",
        "#b07aa1", "#ff9da7", "#9c755f", "#bab0ac",
    ]
    for ax, (cls, column) in zip(axes, layout.items(), strict=True):
        heaps = {heap for heap, _, _ in column}
        members = [b for b in blocks if b.heap in heaps]
        live = live_bytes(members, len(passes))
        bound = max(live, default=0)
        top = max([totals[cls], bound, 1] + [heap_base[b.heap] + b.offset + b.aligned_size for b in members])
        scale, unit = (MIB, "MiB") if top >= MIB else (1024, "KiB") if top >= 1024 else (1, "B")
        unlabeled: list[str] = []
        for k, b in enumerate(members):
            bottom = heap_base[b.heap] + b.offset
            ax.add_patch(Rectangle(
                (b.start - 0.45, bottom / scale), b.end - b.start + 0.9, b.aligned_size / scale,
                facecolor=palette[k % len(palette)], edgecolor="black", linewidth=0.8, alpha=0.85,
                hatch=None if b.aliasable else "//",
            ))
            tall = b.aligned_size / top > 0.08
            if b.aligned_size / top < 0.03 or len(b.name) * 0.09 > b.end - b.start + 0.9:
                unlabeled.append(b.name)  # too small for a legible label: listed in the legend instead
                continue
            ax.text(
                (b.start + b.end) / 2, (bottom + b.aligned_size / 2) / scale,
                f"{b.name}\n{human_bytes(b.size)}" if tall else b.name,
                ha="center", va="center", fontsize=7 if tall else 6, clip_on=True,
            )
        for heap, base, size in column:
            ax.axhline((base + size) / scale, color="black", linestyle=":", linewidth=1.0)
            if size / top > 0.04:
                ax.text(n - 0.45, (base + size) / scale, f"heap {heap} ", ha="right", va="top", fontsize=7)
        ax.step(range(len(live)), [v / scale for v in live], where="mid", color="#666666", linewidth=0.9,
                linestyle=(0, (1, 1)), label="live bytes")
        ax.axhline(bound / scale, color="#d62728", linestyle="--", linewidth=1.2,
                   label=f"lower bound {human_bytes(bound)}")
        ax.plot([], [], color="black", linestyle=":", linewidth=1.0,
                label=f"{len(column)} heap{'s' if len(column) != 1 else ''}: {human_bytes(totals[cls])}")
        if unlabeled:
            shown = ", ".join(unlabeled[:8]) + (f" +{len(unlabeled) - 8}" if len(unlabeled) > 8 else "")
            ax.plot([], [], " ", label=f"too small to label: {shown}")
        ax.set_ylim(0, top / scale * 1.08)
        ax.set_ylabel(f"offset ({unit})")
        ax.set_title(cls, fontsize=9, loc="left")
        ax.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7, framealpha=0.8)
        ax.grid(axis="y", alpha=0.3)
    axes[-1].set_xlim(-0.6, n - 0.4)
    axes[-1].set_xticks(range(len(passes)))
    axes[-1].set_xticklabels([f"{i} {p['name']}" for i, p in enumerate(passes)], rotation=35, ha="right",
                             fontsize=8)
    axes[-1].set_xlabel("pass (executed order); hatched: not aliasable (persistent, imported, output)")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fmt = timeline_format(path)
    fig.savefig(str(path), format=fmt, metadata={"Software": None} if fmt == "png" else None)


TIMELINE_FORMATS = ("png", "svg", "pdf")


def timeline_format(path: str | Path) -> str:
    """The image format named by ``path``'s suffix (png when it has none); ValueError otherwise."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if not suffix:
        return "png"
    if suffix not in TIMELINE_FORMATS:
        raise ValueError(f"cannot draw a timeline as .{suffix}: use {', '.join('.' + f for f in TIMELINE_FORMATS)}")
    return suffix
