"""Draw a placement: pass index across, offset up, one rectangle per resource."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from rgraph.memory.bounds import live_profile
from rgraph.memory.model import Block, Placement


def _mib(n: int) -> str:
    return f"{n / (1 << 20):.1f} MiB"


def draw_timeline(blocks: Sequence[Block], placement: Placement, path_png: str | Path, title: str = "") -> Path:
    """Write a PNG with one subplot per heap; the live-bytes lower bound of the heap's class
    is drawn as a step line. Returns the path written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    by_heap: dict[int, list[tuple[Block, int]]] = {h.id: [] for h in placement.heaps}
    for b in blocks:
        heap_id, offset = placement.offsets[b.name]
        by_heap[heap_id].append((b, offset))
    heaps = [h for h in placement.heaps if by_heap[h.id]] or placement.heaps[:1]
    fig, axes = plt.subplots(len(heaps) or 1, 1, figsize=(11, 2.2 + 2.6 * max(len(heaps), 1)), squeeze=False)
    cmap = plt.get_cmap("tab20")
    stats = placement.stats
    saving = 1 - stats.peak_bytes / stats.unaliased_bytes if stats.unaliased_bytes else 0.0
    fig.suptitle(
        f"{title}  policy={stats.policy}\npeak {_mib(stats.peak_bytes)}, lower bound "
        f"{_mib(stats.lower_bound_bytes)}, unaliased {_mib(stats.unaliased_bytes)} "
        f"(saving {saving:.0%})",
        fontsize=10,
    )
    last_pass = max((b.end for b in blocks), default=0)
    for ax, heap in zip(axes[:, 0], heaps, strict=False):
        placed = by_heap.get(heap.id, [])
        for k, (b, offset) in enumerate(sorted(placed, key=lambda item: item[0].name)):
            width = b.end - b.start + 1
            ax.add_patch(Rectangle((b.start - 0.5, offset), width, max(b.size, 1), facecolor=cmap(k % 20),
                                   edgecolor="black", linewidth=0.4, alpha=0.85))
            if heap.bytes and b.size / heap.bytes > 0.06 and width * 7 >= len(b.name):
                ax.text(b.start - 0.5 + width / 2, offset + b.size / 2, b.name, ha="center", va="center",
                        fontsize=7, clip_on=True)
        same_class = [b for b in blocks if b.memory_class == heap.memory_class]
        times, live = live_profile(same_class)
        if times:
            xs = [t - 0.5 for t in times]
            ax.step(xs, live, where="post", color="red", linewidth=1.2, label="live bytes (lower bound)")
            ax.legend(loc="upper right", fontsize=7)
        ax.set_xlim(-0.5, last_pass + 0.5)
        ax.set_ylim(0, max(heap.bytes, max(live, default=0), 1) * 1.05)
        ax.set_ylabel("offset (bytes)")
        ax.set_title(f"heap {heap.id}: {heap.memory_class}, {_mib(heap.bytes)}", fontsize=9)
    axes[-1, 0].set_xlabel("pass index")
    fig.tight_layout()
    path = Path(path_png)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
