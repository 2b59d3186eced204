"""benchmarks/sweeps.py, the committed sweeps in one command (issue 21 part 3), on lavapipe
under validation at 32x32: with ``--workers 2 --per-worker 4`` two groups of different graphs
(surgery's ``sss``, ``clusters``) go through one pool and each group's outputs equal its own
one-process sweep but the times; benchmarks/sweep_bundle.py packs and unpacks them unchanged."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from locations import ROOT

from rgraph.sweep.same import differences

pytestmark = [pytest.mark.vulkan, pytest.mark.slow]
GROUPS = ("sss", "clusters")


def sweeps(*args: str) -> str:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "sweeps.py"), "--size", "32x32", "--frames", "1",
                           "--validate", "--no-progress", *args], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stderr


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("committed")
    for group in GROUPS:  # the baseline: one process per group
        sweeps("--groups", group, "-o", str(root / "one"))
    err = sweeps("--groups", ",".join(GROUPS), "--workers", "2", "--per-worker", "4", "-o", str(root / "pool"))
    return root, err


def test_one_pool_gives_each_groups_one_process_sweep(runs):
    root, err = runs
    assert "one pool of 2 local worker processes (4 settings each) for all groups" in err
    assert "0 validation message(s)" in (root / "pool" / "accuracy-vs-time.md").read_text()
    for group in GROUPS:
        assert differences(root / "one" / group, root / "pool" / group) == [], group
    summary = (root / "pool" / "accuracy-vs-time.md").read_text()
    assert "## sss" in summary and "## clusters" in summary and "graph `clustered` on `many_lights`" in summary
    assert "cluster_build+light_assign+forward ms" in summary  # the group's own passes' time column


def test_bundle_round_trip(runs, tmp_path):
    root, _ = runs
    bundle = ROOT / "benchmarks" / "sweep_bundle.py"
    for args in (["pack", str(root / "pool"), str(tmp_path / "b")],
                 ["unpack", str(tmp_path / "b" / "sweeps_text.txt"), str(tmp_path / "u")]):
        subprocess.run([sys.executable, str(bundle), *args], check=True, timeout=120, capture_output=True)
    texts = sorted(p.relative_to(root / "pool") for p in (root / "pool").rglob("*") if p.suffix in (".md", ".csv"))
    assert texts and sorted(p.relative_to(tmp_path / "u") for p in (tmp_path / "u").rglob("*") if p.is_file()) == texts
    assert all((tmp_path / "u" / p).read_bytes() == (root / "pool" / p).read_bytes() for p in texts)
    assert (tmp_path / "b" / "pareto_all.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
