"""``rgraph run --timings/--trace``: per-pass GPU intervals per queue from timestamps, and the
Chrome trace event file (a track per queue, passes as slices, barriers, semaphore flows)."""

from __future__ import annotations

import json
import subprocess
import sys

from locations import TESTS

GRAPH = (TESTS / "pass_graphs" / "async_compute.yaml").read_text()


def test_run_writes_intervals_and_a_chrome_trace(tmp_path):
    graph, timings, trace = tmp_path / "g.yaml", tmp_path / "t.json", tmp_path / "trace.json"
    graph.write_text(GRAPH)
    run = subprocess.run([sys.executable, "-m", "rgraph", "run", str(graph), "--size", "32x32", "--frames", "3",
                          "--timings", str(timings), "--trace", str(trace)], capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr
    t = json.loads(timings.read_text())
    assert t["size"] == [32, 32] and set(t["intervals"]) == {"prepass", "gbuffer", "ao", "light"}
    iv = t["intervals"]
    assert iv["ao"]["queue"] == "compute" and iv["light"]["queue"] == "graphics"
    for name, x in iv.items():
        assert 0.0 <= x["start_ms"] <= x["end_ms"], name
    assert iv["ao"]["start_ms"] >= iv["prepass"]["end_ms"] - 1e-6   # ao waits for the prepass (semaphore)
    assert iv["light"]["start_ms"] >= iv["ao"]["end_ms"] - 1e-6     # light waits for ao
    events = json.loads(trace.read_text())["traceEvents"]
    threads = {e["args"]["name"] for e in events if e["ph"] == "M" and e["name"] == "thread_name"}
    assert {"graphics queue", "compute queue", "submit"} <= threads
    slices = {e["name"]: e for e in events if e["ph"] == "X" and e["cat"] != "cpu"}
    assert set(slices) == {"prepass", "gbuffer", "ao", "light"}
    assert abs(slices["ao"]["ts"] - iv["ao"]["start_ms"] * 1000) < 1e-3 and slices["ao"]["args"]["timestamps"]
    starts = [e for e in events if e["ph"] == "s"]
    finishes = [e for e in events if e["ph"] == "f"]
    assert starts and sorted(e["id"] for e in starts) == sorted(e["id"] for e in finishes)
    assert any(e["ph"] == "i" and e["cat"] == "barrier" for e in events)
    assert any(e["ph"] == "X" and e["cat"] == "cpu" for e in events)
