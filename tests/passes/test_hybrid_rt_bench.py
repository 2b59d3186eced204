"""benchmarks/hybrid_rt.py on lavapipe: one device, every plan warmed up, then timed in
alternating chunks; the row carries the study's columns for the hybrid (and the hardware-raster
variant when its graph exists)."""

from __future__ import annotations

import json

import pytest

from rgraph.vk.errors import VulkanUnavailable


def test_merge_takes_the_median_of_the_chunks():
    from benchmarks.hybrid_rt import _merge

    chunks = [{"total_ms": t, "frames": 2, "passes": {"a": t / 2, "b": None},
               "intervals": {"a": {"end_ms": t / 4}}} for t in (1.0, 9.0, 2.0)]
    merged = _merge(chunks)
    assert merged["total_ms"] == 2.0 and merged["passes"] == {"a": 1.0, "b": None}
    assert merged["end_ms"] == {"a": 0.5} and merged["frames"] == 6


@pytest.mark.vulkan
def test_small_run_alternates_the_plans_on_one_device(tmp_path, monkeypatch):
    from benchmarks import hybrid_rt

    loads: list[str] = []
    runs: list[str] = []
    real = hybrid_rt.side_by_side

    def spy(gpu, plans, frames, warmup_s, chunk):
        loads.extend(plans)
        names = {id(plan): name for name, plan in plans.items()}
        original_load = gpu.load

        def load(plan, **kw):
            exe = original_load(plan, **kw)
            run = exe.run
            name = names[id(plan)]
            exe.run = lambda n, *a, _name=name, **k: (runs.append(_name), run(n, *a, **k))[1]
            return exe
        gpu.load = load
        try:
            return real(gpu, plans, frames, warmup_s, chunk)
        finally:
            gpu.load = original_load

    monkeypatch.setattr(hybrid_rt, "side_by_side", spy)
    out = tmp_path / "rows.jsonl"
    try:
        code = hybrid_rt.main(["--size", "32x18", "--scenes", "rt_gallery", "--cameras", "3", "--frames", "2",
                               "--chunk", "1", "--warmup", "0.01", "--json", str(out)])
    except VulkanUnavailable as exc:  # pragma: no cover
        pytest.skip(str(exc))
    assert code == 0
    (row,) = [json.loads(line) for line in out.read_text().splitlines()]
    for key in ("T_ms", "t_a_ms", "t_a_over_T", "t_b_ms", "t_ms", "t_over_T", "psnr_db", "ssim", "traced_share"):
        assert row[key] is not None, key
    assert row["t_ms"] == pytest.approx(row["t_a_ms"] + row["t_b_ms"])
    assert row["t_over_T"] == pytest.approx(row["t_ms"] / row["T_ms"])
    assert row["psnr_db"] >= 45
    assert "alone" in loads and "hybrid" in loads
    timed = runs[-2 * len(loads):]  # two timed chunks of one frame each per plan, alternating, order rotated
    first, second = timed[:len(loads)], timed[len(loads):]
    assert sorted(first) == sorted(second) == sorted(set(runs)) and first != second
