"""Several sweeps through one worker pool (``rgraph.sweep.pool.run_groups``) on lavapipe under
validation: every group's outputs equal its own one-process ``rgraph sweep`` except measured
times, whatever the pool (a process per setting, or several settings per process); a setting
killed twice is reported in its group while every other setting of every group renders; all
references are scheduled first, then groups in order, those whose reference landed first."""

from __future__ import annotations

import pytest
import sweep_helpers
from sweep_helpers import ARGS, rows, sweep

from rgraph.sweep.parallel import Executor, ProcessBackend
from rgraph.sweep.pool import Group, _items, run_groups
from rgraph.sweep.remote import KILL_ENV
from rgraph.sweep.runner import SweepRequest, prepare
from rgraph.sweep.same import differences
from rgraph.sweep.settings import parse_assignments, parse_knob
from rgraph.sweep.writers import write_sweep

pytestmark = pytest.mark.vulkan
one_process = sweep_helpers.one_process  # group "a": ARGS in one process (a fixture)

B_KNOBS, B_REFERENCE = ["aa.samples=3"], ["aa.samples=4"]
B_ARGS = [*ARGS[:ARGS.index("--knob")], "--knob", B_KNOBS[0], "--reference", B_REFERENCE[0],
          "--hdr", "hdr", "--validate", "--no-progress"]


@pytest.fixture(scope="module")
def one_process_b(tmp_path_factory):
    """Group "b" (other knob values and reference) in one process."""
    out = tmp_path_factory.mktemp("one_b") / "sweep"
    assert sweep([*B_ARGS, "-o", str(out)]) == 0
    return out


def request(knobs, reference):
    return SweepRequest(graph=ARGS[0], knobs=[parse_knob(k) for k in knobs],
                        reference=parse_assignments(reference, "--reference"), size=(48, 48), frames=2,
                        hdr="hdr", validate=True)


def groups(root):
    return [Group("a", request(["aa.samples=1,2"], ["aa.samples=8"]), root / "a"),
            Group("b", request(B_KNOBS, B_REFERENCE), root / "b")]


def run_and_write(root, backend):
    written = []

    def done(group, result):
        assert not isinstance(result, Exception), result
        write_sweep(result, group.out_dir)
        written.append(group.name)

    with Executor(backend) as executor:
        results = run_groups(groups(root), executor, done=done)
    return results, written


@pytest.mark.parametrize("per_worker", [1, 3])
def test_one_pool_gives_every_groups_own_sweep(one_process, one_process_b, tmp_path, per_worker):
    results, written = run_and_write(tmp_path, ProcessBackend(2, tasks_per_worker=per_worker))
    assert sorted(written) == ["a", "b"]  # each written once, when its last rendering landed
    assert all(r.messages() == [] for r in results.values())  # zero validation messages
    assert differences(one_process, tmp_path / "a") == []
    assert differences(one_process_b, tmp_path / "b") == []


def test_a_setting_killed_twice_is_reported_in_its_group_only(one_process, one_process_b, tmp_path,
                                                               monkeypatch):
    monkeypatch.setenv(KILL_ENV, "aa.samples=1")  # only group "a" has this setting
    results, _ = run_and_write(tmp_path, ProcessBackend(2, tasks_per_worker=2))
    a = results["a"]
    assert list(a.failures) == ["aa.samples=1"]
    assert a.failures["aa.samples=1"] == ("attempt 1: worker process killed by signal 9; "
                                          "attempt 2: worker process killed by signal 9")
    got, want = rows(tmp_path / "a"), rows(one_process)
    assert got["aa.samples=1"]["psnr"] == got["aa.samples=1"]["image"] == ""
    for label in ("reference", "default", "aa.samples=2"):
        assert got[label]["psnr"] == want[label]["psnr"] and got[label]["image"] == want[label]["image"]
    assert results["b"].failures == {} and differences(one_process_b, tmp_path / "b") == []


def test_references_first_then_groups_in_turn_ready_ones_first(tmp_path):
    sweeps = {g.name: prepare(g.request, g.out_dir) for g in groups(tmp_path)}
    items = _items(groups(tmp_path), sweeps, None)
    first = [next(items) for _ in range(2)]
    assert [(k[0], job.setting.label) for k, job in first] == [("a", "reference"), ("b", "reference")]
    assert all(job.reference is None for _, job in first)
    sweeps["b"].collector.reference_images = lambda: "b's reference images"  # b's reference landed
    nxt = [next(items) for _ in range(2)]
    assert [k[0] for k, _ in nxt] == ["b", "b"]  # b's settings first: their workers compare
    assert all(job.reference == "b's reference images" for _, job in nxt)
    rest = list(items)
    assert [k[0] for k, _ in rest] == ["a", "a"] and all(job.reference is None for _, job in rest)
    assert {job.setting.label for _, job in rest} == {"default", "aa.samples=1"}


def test_groups_in_order_while_no_reference_landed(tmp_path):
    sweeps = {g.name: prepare(g.request, g.out_dir) for g in groups(tmp_path)}
    names = [k[0] for k, _ in _items(groups(tmp_path), sweeps, None)]
    assert names == ["a", "b", "a", "a", "b", "b"]  # references, then a's settings, then b's


def test_group_names_must_differ(tmp_path):
    a = groups(tmp_path)[0]
    with pytest.raises(ValueError, match="group names must be unique"):
        run_groups([a, a], Executor(ProcessBackend(1)))
