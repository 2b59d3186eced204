"""rgraph.vk.multi.spans: a device's GPU span must cover every pass of its plan and fit in the
host interval that waited for it (pure logic on timings dicts)."""

from __future__ import annotations

from rgraph.vk.multi.spans import span_findings

PLAN = {"passes": [{"name": "a"}, {"name": "b"}]}


def _timings(span, intervals):
    return {"total_ms": span, "intervals": {n: {"start_ms": s, "end_ms": e} for n, (s, e) in intervals.items()}}


def test_a_span_covering_every_pass_inside_its_host_wait_is_clean():
    assert span_findings(1, PLAN, _timings(2.0, {"a": (0.0, 1.0), "b": (1.0, 2.0)}), host_ms=3.0) == []


def test_a_pass_without_timestamps_is_reported():
    (finding,) = span_findings(1, PLAN, _timings(2.0, {"a": (0.0, 2.0)}), host_ms=3.0)
    assert "device 1" in finding and "'b'" in finding


def test_a_pass_outside_the_span_is_reported():
    (finding,) = span_findings(0, PLAN, _timings(1.0, {"a": (0.0, 1.0), "b": (0.5, 1.5)}), host_ms=3.0)
    assert "outside the span" in finding


def test_a_span_longer_than_the_host_wait_is_reported():
    (finding,) = span_findings(0, PLAN, _timings(5.0, {"a": (0.0, 1.0), "b": (1.0, 5.0)}), host_ms=3.0)
    assert "exceeds" in finding


def test_no_timestamps_at_all_is_reported():
    assert span_findings(0, PLAN, {"total_ms": None}, host_ms=1.0) == ["device 0: no timestamps (no GPU span)"]
