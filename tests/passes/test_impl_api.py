"""The pass-implementation API end to end on lavapipe: registry, setup helpers, inputs, outputs."""

from __future__ import annotations

import impl_fixtures.passes  # noqa: F401 -- registers test_scale and test_blit
import numpy as np
import pytest
from locations import TESTS

from rgraph import impl
from rgraph.compiler.pipeline import compile_graph
from rgraph.vk.texels import decode, encode

GRAPH = TESTS / "impl_fixtures" / "graph.yaml"


def test_registry_lists_and_rejects():
    assert {"test_scale", "test_blit"} <= set(impl.names())
    with pytest.raises(KeyError, match="no pass implementation named 'nope'"):
        impl.lookup("nope")


@pytest.mark.parametrize("fmt", ["r8g8b8a8_unorm", "r8g8b8a8_srgb", "r16g16b16a16_sfloat", "r32_sfloat", "r8_unorm",
                                 "b8g8r8a8_unorm", "r16g16_sfloat"])
def test_texel_codec_round_trip(fmt):
    rng = np.random.default_rng(1)
    channels = {"r8g8b8a8": 4, "b8g8r8a8": 4, "r16g16b16a16": 4, "r32": 1, "r8": 1, "r16g16": 2}[fmt.rsplit("_", 1)[0]]
    values = rng.random((3, 5, channels)).astype(np.float32)
    back = decode(fmt, encode(fmt, values), 5, 3)
    tol = 2e-3 if "16" in fmt else 1e-6 if "32" in fmt else 1 / 255 * (3 if "srgb" in fmt else 0.51)
    assert np.abs(back - values).max() <= tol


@pytest.mark.vulkan
def test_impl_passes_run_clean_and_compute_what_they_say():
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPH, size=(19, 13), params={"scale.gain": "3.0"})
    rng = np.random.default_rng(7)
    src = rng.uniform(-2, 2, (13, 19, 4)).astype(np.float32)
    result = execute_plan(plan, validate=True, frames=3, inputs={"src": src}, read_outputs=True)
    assert [m.text for m in result.messages] == []
    assert result.data_ok is None and result.unchecked  # implemented passes: no probe prediction
    out = result.outputs["out"]
    want = np.float16(src) * np.float32(3.0)
    np.testing.assert_allclose(out[..., :3], np.float16(want)[..., :3], rtol=2e-3, atol=2e-3)
    assert np.all(out[..., 3] == 2.0)  # the tint uniform of the last frame (frame index 2)
    assert set(result.timings["passes"]) == {"scale", "blit"}


@pytest.mark.vulkan
def test_unknown_impl_is_a_clear_error(tmp_path):
    from rgraph.vk.errors import ExecutionError
    from rgraph.vk.executor import execute_plan

    plan = compile_graph(GRAPH, size=(8, 8))
    plan["passes"][0]["impl"] = "missing_impl"
    with pytest.raises(ExecutionError, match="no pass implementation named 'missing_impl'"):
        execute_plan(plan)
