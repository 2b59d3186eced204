"""Which passes a knob changes (rgraph.sweep.affected): through resources sized by the knob
(compiled surgery plans), through the params an implementation looked up (recorded by
PassSetup.params on lavapipe under validation), and the per-knob time axis of the plots."""

from __future__ import annotations

import copy

import pytest
import sweep_fixtures.passes as zoneplate  # registers the fixture's pass implementations

from rgraph.compiler.pipeline import compile_graph
from rgraph.sweep.affected import changed_passes, passes_ms
from rgraph.sweep.runner import SweepRequest, run_sweep
from rgraph.sweep.settings import parse_knob
from rgraph.sweep.writers import knob_axis, markdown, row_ms


def _surgery(**params):
    return compile_graph("surgery", params={k: str(v) for k, v in params.items()}, size=(64, 64))


def test_resources_sized_by_the_knob():
    small, large = _surgery(**{"shadow.size": 256}), _surgery(**{"shadow.size": 512})
    # shadow_maps is "${params.shadow.size}" square: its writer and its reader change; the
    # heap offsets of every other resource move too, and do not count
    assert changed_passes("shadow.size", [small, large], [{}, {}]) == ["shadow", "forward"]
    quarter, half = _surgery(**{"hbao.scale": 0.25}), _surgery(**{"hbao.scale": 0.5})
    assert changed_passes("hbao.scale", [quarter, half], [{}, {}]) == ["hbao_downsample", "hbao", "hbao_upsample"]


def test_params_looked_up_pass_params_and_culled_passes():
    plan = _surgery()
    assert changed_passes("hbao.steps", [plan, plan], [{}, {}]) == []
    assert changed_passes("hbao.steps", [plan, plan], [{"hbao": ["hbao.steps"]}, {"forward": ["x"]}]) == ["hbao"]
    other = copy.deepcopy(plan)
    other["passes"] = [p for p in other["passes"] if p["name"] != "decals"]
    next(p for p in other["passes"] if p["name"] == "bloom_blur_h")["params"]["bloom.direction"] = "v"
    assert changed_passes("k", [plan, other], [{}, {}]) == ["decals", "bloom_blur_h"]


def test_passes_ms():
    assert passes_ms({"a": 1.0, "b": 2.5, "c": 9.0}, ["a", "b"]) == 3.5
    assert passes_ms({"a": 1.0}, ["a", "culled"]) == 1.0  # a pass that did not run costs nothing
    assert passes_ms({"a": None, "b": 1.0}, ["a", "b"]) is None
    assert passes_ms({}, ["a"]) is None  # a setting that was not rendered


@pytest.mark.vulkan
def test_sweep_plots_each_knob_against_its_passes(tmp_path):
    from rgraph.vk.errors import VulkanUnavailable

    request = SweepRequest(graph=str(zoneplate.GRAPH), knobs=[parse_knob("aa.samples=1,3"),
                                                              parse_knob("zone.intensity=2")],
                           size=(16, 16), frames=1, validate=True)
    try:
        result = run_sweep(request, tmp_path, progress=False)
    except VulkanUnavailable as exc:  # pragma: no cover - environment without Vulkan
        pytest.skip(str(exc))
    assert result.messages() == []
    # both params are looked up by the zone plate's implementation only; the tonemap pass
    # reads the HDR image, whose description no knob changes
    assert result.knob_passes == {"aa.samples": ["zoneplate"], "zone.intensity": ["zoneplate"]}
    passes, label = knob_axis(result, "aa.samples")
    assert passes == ["zoneplate"] and label == "GPU time of zoneplate (ms, median)"
    for row in result.rows:
        assert row_ms(row, passes) == row.pass_ms["zoneplate"] < row.total_ms
    assert "- `aa.samples`: `zoneplate`" in markdown(result, {}, None)
