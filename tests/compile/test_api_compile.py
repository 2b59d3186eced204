"""The compile side of the Python API: rgraph.load, rgraph.compile, Compiled."""

from __future__ import annotations

import subprocess
import sys

import pytest
from locations import ROOT, TESTS

import rgraph
from rgraph.errors import RGraphError
from rgraph.memory_requirements import ProfileMemoryRequirements
from rgraph.plan import Plan
from rgraph.resources import graphs_dir

CCT = graphs_dir() / "scenes" / "cct.yaml"


def test_compile_matches_the_golden_plan(tmp_path):
    compiled = rgraph.compile("surgery", scene=CCT, size=(320, 180))
    assert isinstance(compiled.plan, Plan)
    golden = (TESTS / "golden" / "surgery_cct.json").read_text()
    assert compiled.as_json().replace(str(graphs_dir()), "<graphs>") == golden
    path = compiled.save(tmp_path / "plan.json")
    assert path.read_text() == compiled.as_json()
    assert rgraph.load_plan(path) == compiled.plan


def test_load_then_compile_is_compile_of_the_path():
    spec = rgraph.load("surgery", scene=CCT, size=(320, 180), params={"hbao.directions": 4, "ibl.static": 0})
    assert spec.params["hbao.directions"] == 4 and spec.params["ibl.static"] == 0
    assert rgraph.compile(spec).plan == rgraph.compile("surgery", scene=CCT, size=(320, 180),
                                                        params={"hbao.directions": "4", "ibl.static": "0"}).plan


def test_memory_analysis_agrees_with_the_plan():
    compiled = rgraph.compile("surgery", scene=CCT, size=(320, 180), policy="tlsf")
    m = compiled.memory_analysis()
    stats = compiled.plan.stats
    assert (m.policy, m.peak_bytes, m.lower_bound_bytes, m.unaliased_bytes) == (
        "tlsf", stats.peak_bytes, stats.lower_bound_bytes, stats.unaliased_bytes)
    assert sum(h.bytes for h in m.heaps) == m.peak_bytes and m.allocations == len(m.heaps)
    placed = sorted(n for h in m.heaps for n in h.resources)
    assert placed == sorted(r.name for r in compiled.plan.resources)
    assert m.lower_bound_bytes <= m.peak_bytes <= m.unaliased_bytes and m.ratio >= 1.0


def test_as_text_is_the_inspect_summary():
    text = rgraph.compile("surgery", scene=CCT, size=(320, 180)).as_text()
    assert "Schedule (" in text and "graph    surgery" in text and "peak" in text


class _Device:
    """Stands in for rgraph.open_device()'s Gpu: only memory_requirements() is used."""

    def __init__(self) -> None:
        self.calls = 0

    def memory_requirements(self):
        self.calls += 1
        return ProfileMemoryRequirements.named("lavapipe")


def test_device_provides_the_requirements():
    gpu = _Device()
    by_device = rgraph.compile("surgery", scene=CCT, size=(320, 180), device=gpu).plan
    by_profile = rgraph.compile("surgery", scene=CCT, size=(320, 180), profile="lavapipe").plan
    assert gpu.calls == 1
    assert by_device.device_profile == "device" and by_profile.device_profile == "lavapipe"
    assert by_device.resources == by_profile.resources and by_device.passes == by_profile.passes


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"device": _Device(), "profile": "lavapipe"}, "give one of device=, profile=, memory=; got device, profile"),
    ({"device": object()}, "device= needs a memory_requirements() method, got object"),
    ({"policy": "nonsense"}, "--policy"),
])
def test_bad_arguments(kwargs, message):
    with pytest.raises(RGraphError) as info:
        rgraph.compile("surgery", size=(64, 64), **kwargs)
    assert message in str(info.value)


def test_size_is_refused_for_a_loaded_spec():
    spec = rgraph.load("surgery", size=(64, 64))
    with pytest.raises(RGraphError, match="size only apply to a graph file"):
        rgraph.compile(spec, size=(32, 32))


def test_spec_is_not_mutated_by_compiling():
    spec = rgraph.load("surgery", size=(64, 64))
    before = (list(spec.outputs), spec.scene_source, [p.name for p in spec.passes])
    rgraph.compile(spec, extra_outputs=["hdr"])
    assert (list(spec.outputs), spec.scene_source, [p.name for p in spec.passes]) == before


def test_import_rgraph_is_cheap():
    code = ("import sys, rgraph; heavy = [m for m in ('rgraph.compiler', 'rgraph.vk', 'vulkan', 'numpy', 'pydantic')"
            " if m in sys.modules]; print(heavy)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert out.stdout.strip() == "[]"


def test_schedule_matches_the_command_line(tmp_path):
    from rgraph.cli import main

    out = tmp_path / "p.json"
    assert main(["compile", "surgery", "--size", "64x64", "--schedule", "async-early", "-o", str(out)]) == 0
    compiled = rgraph.compile("surgery", size=(64, 64), schedule="async-early")
    assert compiled.plan.stats.schedule == "async-early"
    assert compiled.as_json() == out.read_text()
