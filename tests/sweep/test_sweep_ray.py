"""``rgraph sweep --ray`` on a local Ray cluster (``ray.init(num_cpus=2)``, one for the
module) on lavapipe under validation: the same outputs as the one-process sweep except
measured times; a task whose worker is SIGKILLed once is retried."""

from __future__ import annotations

import pytest
import sweep_helpers
from sweep_helpers import ARGS, rows, sweep

from rgraph.sweep.remote import KILL_ENV
from rgraph.sweep.same import differences

ray = pytest.importorskip("ray")
pytestmark = pytest.mark.vulkan
one_process = sweep_helpers.one_process  # the module-scoped one-process sweep (a fixture)


@pytest.fixture(scope="module")
def cluster():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        yield
    finally:
        ray.shutdown()


def test_ray_sweep(cluster, one_process, tmp_path, monkeypatch, capsys):
    """One test, so that one cluster starts even when xdist spreads a module's tests.

    The reference's task is SIGKILLed once: it is retried and the outputs are the
    one-process sweep's but its times. Then a setting's task is killed on both attempts: it
    is reported and the others render."""
    marker = tmp_path / "killed-once"
    monkeypatch.setenv(KILL_ENV, f"reference@{marker}")
    out = tmp_path / "ray"
    assert sweep([*ARGS, "--ray", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "in Ray (local), one task per worker process, num_cpus=1" in err
    assert "0 validation message(s)" in err
    assert marker.is_file()  # the first attempt's worker really died
    assert differences(one_process, out) == []
    assert ray.is_initialized()  # a cluster the caller started is left running

    monkeypatch.setenv(KILL_ENV, "aa.samples=1")
    assert sweep([*ARGS, "--ray", "-o", str(tmp_path / "twice")]) == 1
    err = capsys.readouterr().err
    assert "setting aa.samples=1 failed: attempt 1: Ray task lost: " in err and "attempt 2: Ray task lost" in err
    assert rows(tmp_path / "twice")["reference"]["image"] == "images/reference.png"
