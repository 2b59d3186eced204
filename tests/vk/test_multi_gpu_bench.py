"""benchmarks/multi_gpu.py on lavapipe, tiny: every configuration is measured the same way
(warm-up, frame counts), spans cover each device's passes, zero validation messages."""

from __future__ import annotations

import json

from benchmarks import multi_gpu


def test_benchmark_measures_every_configuration_alike(tmp_path):
    out = tmp_path / "multi.json"
    status = multi_gpu.main(["--devices", "0,0", "--size", "48x32", "--frames", "2", "--rounds", "2",
                             "--warmup-s", "0.05", "--graphs", "probe,mesh", "--splits", "sort-last",
                             "--pipelined", "off,on", "--triangles", "4000", "--chunks", "4", "--validate",
                             "--out-json", str(out)])
    assert status == 0
    data = json.loads(out.read_text())
    rows = data["rows"]
    assert data["messages"] == 0
    assert [r["config"] for r in rows if r["graph"] == "mesh"] == [
        "one device", "sort-last shared", "sort-last shared pipe", "sort-last staged", "sort-last staged pipe"]
    assert {r["frames"] for r in rows} == {4} and {r["stream_batches"] for r in rows} == {2}
    for r in rows:
        assert r["findings"] == []
        assert r["warmup"]["seconds"] >= 0.05 and r["warmup"]["frames"] >= 2
        assert len(r["gpu_ms"]) == (1 if r["split"] is None else 2)
        assert all(0 < ms <= r["serial_wall_ms"] for ms in r["gpu_ms"])  # a device's span lies inside the frame
        assert r["efficiency"] == r["speedup"] / len(r["gpu_ms"])
    shared = [r for r in rows if r["transfer"] == "shared"]
    assert shared and all(r["copy_ms"] == 0.0 for r in shared)
    assert all(r["copy_ms"] > 0 for r in rows if r["transfer"] == "staged")


def test_benchmark_dynamic_balance_configuration(tmp_path):
    out = tmp_path / "dyn.json"
    assert multi_gpu.main(["--devices", "0,0", "--size", "48x32", "--frames", "2", "--rounds", "1",
                           "--warmup-s", "0.05", "--graphs", "pixels", "--iterations", "8", "--transfers", "shared",
                           "--pipelined", "off", "--validate", "--out-json", str(out)]) == 0
    rows = json.loads(out.read_text())["rows"]
    assert [r["config"] for r in rows] == ["one device", "sort-first shared", "sort-first shared dyn"]
    dyn = rows[-1]
    assert dyn["balance"] == "dynamic" and dyn["plan_loads"] >= 1 and sum(dyn["bands"][0]) == 32
    assert dyn["findings"] == [] and dyn["frames"] == 2
