"""The small zone-plate sweep the worker and Ray tests run, its one-process result (a
module-scoped fixture: import it into the test module) and the CLI entry point."""

from __future__ import annotations

import csv

import pytest
import sweep_fixtures.passes as zoneplate  # registers the fixture's pass implementations

from rgraph.cli import main

ARGS = [str(zoneplate.GRAPH), "--size", "48x48", "--frames", "2", "--knob", "aa.samples=1,2",
        "--reference", "aa.samples=8", "--hdr", "hdr", "--validate", "--no-progress"]


def sweep(argv):
    from rgraph.vk.errors import VulkanUnavailable

    try:
        return main(["sweep", *argv])
    except VulkanUnavailable as exc:  # pragma: no cover - environment without Vulkan
        pytest.skip(str(exc))


def rows(out):
    with (out / "sweep.csv").open() as f:
        return {r["setting"]: r for r in csv.DictReader(f)}


@pytest.fixture(scope="module")
def one_process(tmp_path_factory):
    """The sweep of ARGS in this process, every setting one after the other."""
    out = tmp_path_factory.mktemp("one") / "sweep"
    assert sweep([*ARGS, "-o", str(out)]) == 0
    return out
