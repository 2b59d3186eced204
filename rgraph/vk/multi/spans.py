"""Sanity of one device's GPU span for one frame (issue 16: a benchmark's figures are only as
good as what each device's span covers).

A device's span is its frame's last pass end minus its first pass start (the executor's
``total_ms``). It describes the device's whole frame only if every pass of the device's plan
has a timestamp pair inside it, and it cannot be longer than the host interval that
submitted that frame and waited for it.
"""

from __future__ import annotations

from typing import Any

EPS_MS = 1e-3


def span_findings(device: int, plan: dict, timings: dict[str, Any], host_ms: float) -> list[str]:
    """Why ``timings`` (one frame of one device, ``Executable.run(1)``) do not describe the
    device's whole frame; [] when they do."""
    span = timings.get("total_ms")
    if span is None:
        return [f"device {device}: no timestamps (no GPU span)"]
    out = []
    intervals = timings.get("intervals") or {}
    for p in plan["passes"]:
        iv = intervals.get(p["name"])
        if iv is None:
            out.append(f"device {device}: pass {p['name']!r} has no timestamps")
        elif not (-EPS_MS <= iv["start_ms"] <= iv["end_ms"] <= span + EPS_MS):
            out.append(f"device {device}: pass {p['name']!r} [{iv['start_ms']:.4f}, {iv['end_ms']:.4f}] ms lies "
                       f"outside the span of {span:.4f} ms")
    if span > host_ms + EPS_MS:
        out.append(f"device {device}: GPU span {span:.4f} ms exceeds the {host_ms:.4f} ms the host waited for it")
    return out
