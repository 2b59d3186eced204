"""``rgraph run --trace OUT.json``: a frame in the Chrome trace event format.

Opens in Perfetto (ui.perfetto.dev, offline too) and chrome://tracing. One process per
device with one thread (track) per queue; passes are complete ("X") slices at their median
GPU start and end within the frame (timestamps; laid out from per-pass medians when the
timings have none); each pass's barriers are an instant event at its start and its
queue-family releases one at its end; every semaphore wait is a flow arrow from the
signalling pass to the waiting one; the CPU's median submit time is its own track.
Times are microseconds (the format's unit).
"""

from __future__ import annotations

from typing import Any

from rgraph.report.barriers import barrier_text
from rgraph.report.html_svg import gpu_layout

Plan = dict[str, Any]
CPU_PID = 1000


def _meta(pid: int, tid: int | None, kind: str, name: str) -> dict[str, Any]:
    event: dict[str, Any] = {"ph": "M", "pid": pid, "name": kind, "args": {"name": name}}
    if tid is not None:
        event["tid"] = tid
    return event


def chrome_trace(plan: Plan, timings: dict[str, Any]) -> dict[str, Any]:
    """The trace document ``{"traceEvents": [...], "displayTimeUnit": "ms", "otherData": {...}}``."""
    rows = gpu_layout(plan, timings)
    queues = list(dict.fromkeys([*(plan.get("queues") or []), *(r["queue"] for r in rows)]))
    tid = {q: i for i, q in enumerate(queues)}
    devices = sorted({p.get("device", 0) for p in plan["passes"]}) or [0]
    device_name = str(timings.get("device") or "GPU")
    events: list[dict[str, Any]] = []
    for d in devices:
        events.append(_meta(d, None, "process_name", f"device {d}: {device_name}"))
        for q, t in tid.items():
            events.append(_meta(d, t, "thread_name", f"{q} queue"))
    events.append(_meta(CPU_PID, None, "process_name", "CPU"))
    events.append(_meta(CPU_PID, 0, "thread_name", "submit"))
    ends: dict[tuple[str, int], tuple[int, int, float]] = {}
    for r, p in zip(rows, plan["passes"], strict=True):
        pid, t = p.get("device", 0), tid[r["queue"]]
        start, end = r["start"] * 1000.0, r["end"] * 1000.0
        events.append({"ph": "X", "name": p["name"], "cat": p.get("kind") or "pass", "pid": pid, "tid": t,
                       "ts": start, "dur": max(end - start, 0.0),
                       "args": {"index": p.get("index"), "impl": p.get("impl") or "probe",
                                "median_ms": r["ms"], "barriers": len(p.get("barriers") or []),
                                "timestamps": bool(r.get("timestamps"))}})
        if p.get("barriers"):
            events.append({"ph": "i", "s": "t", "name": f"{len(p['barriers'])} barrier(s) before {p['name']}",
                           "cat": "barrier", "pid": pid, "tid": t, "ts": start,
                           "args": {"barriers": [barrier_text(b, "acquire") for b in p["barriers"]]}})
        if p.get("releases"):
            events.append({"ph": "i", "s": "t", "name": f"{len(p['releases'])} release(s) after {p['name']}",
                           "cat": "barrier", "pid": pid, "tid": t, "ts": end,
                           "args": {"releases": [barrier_text(b, "release") for b in p["releases"]]}})
        for s in p.get("signals") or []:
            ends[(s["queue"], s["value"])] = (pid, t, end)
    flow = 0
    for r, p in zip(rows, plan["passes"], strict=True):
        for w in p.get("waits") or []:
            src = ends.get((w["queue"], w["value"]))
            if src is None:
                continue
            flow += 1
            name = f"{w['queue']} timeline >= {w['value']}"
            events.append({"ph": "s", "id": flow, "name": name, "cat": "semaphore", "pid": src[0], "tid": src[1],
                           "ts": max(src[2] - 0.001, 0.0)})
            events.append({"ph": "f", "bp": "e", "id": flow, "name": name, "cat": "semaphore",
                           "pid": p.get("device", 0), "tid": tid[r["queue"]], "ts": r["start"] * 1000.0 + 0.001})
    cpu = timings.get("cpu_submit_ms")
    if isinstance(cpu, (int, float)):
        events.append({"ph": "X", "name": "submit frame (median)", "cat": "cpu", "pid": CPU_PID, "tid": 0,
                       "ts": 0.0, "dur": cpu * 1000.0})
    return {"traceEvents": events, "displayTimeUnit": "ms",
            "otherData": {"graph": plan.get("graph"), "size": plan.get("size"), "frames": timings.get("frames"),
                          "device": device_name, "total_ms": timings.get("total_ms")}}
