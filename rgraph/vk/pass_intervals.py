"""Per-pass GPU start/end times from the timestamp rows the executor collects.

Each frame's row holds a (start, end) timestamp pair per pass. Times are made relative to
the frame's earliest timestamp and the median over frames is taken, so a pass's interval
says where in the frame it ran on its queue. Timestamps of one device share a time domain
on the GPUs this runs on (lavapipe, NVIDIA); comparing queues relies on that.
"""

from __future__ import annotations

from typing import Any


def pass_intervals(plan: dict, rows: Any, period_ms: float) -> dict[str, dict[str, Any]]:
    """{pass: {"queue", "device", "start_ms", "end_ms"}} (medians over frames); {} without rows."""
    import numpy as np

    if not len(rows):
        return {}
    stamps = rows.astype(np.float64)
    origin = stamps.min(axis=1, keepdims=True)
    starts = np.median(stamps[:, 0::2] - origin, axis=0) * period_ms
    ends = np.median(stamps[:, 1::2] - origin, axis=0) * period_ms
    return {p["name"]: {"queue": p.get("queue") or "graphics", "device": p.get("device", 0),
                        "start_ms": float(starts[i]), "end_ms": float(ends[i])}
            for i, p in enumerate(plan["passes"])}
