"""The hybrid's compute shading pass (``rt_hybrid_first``, passes/raytrace_first.py;
benchmarks/graphs/rt_hybrid_first.yaml) on lavapipe: it finishes the pixels that need no ray and
lists exactly the others for the shade pass, whose indirect trace then covers only those, and
the image is the one the bundled hybrid (graphs/rt_hybrid.yaml: the shade pass over every pixel)
gives."""

from __future__ import annotations

import numpy as np
import pytest
from locations import ROOT
from rt_helpers import run_rt

from rgraph.resources import builtin_passes

builtin_passes()
from rgraph.passes.raytrace_hybrid import (  # noqa: E402
    decode_visibility,
    instance_materials,
    needs_secondary_rays,
    prim_bits,
)

FIRST = str(ROOT / "benchmarks" / "graphs" / "rt_hybrid_first.yaml")
TIR = ROOT / "tests" / "data" / "rt" / "wave_tir.yaml"  # a directional and a point light, glass
TINY = ROOT / "graphs" / "scenes" / "rt_tiny.yaml"
SIZE = 32


def _run(graph, scene, params=None, extra=()):
    return run_rt(graph, scene, (SIZE, SIZE), params, extra, frames=2)[1]


def _image(outputs) -> np.ndarray:
    return outputs["color"][..., :3].astype(np.float64)


def listed_pixels(outputs) -> tuple[int, np.ndarray]:
    """(count, boolean mask of the listed pixels) from first_args / first_list."""
    count = int(np.frombuffer(outputs["first_args"].tobytes()[:16], dtype=np.uint32)[0])
    entries = outputs["first_list"][..., 0].ravel()[:count].astype(np.int64)
    mask = np.zeros((SIZE, SIZE), dtype=bool)
    ys, xs = entries >> 16, entries & 0xFFFF
    assert (xs < SIZE).all() and (ys < SIZE).all()
    mask[ys, xs] = True
    assert mask.sum() == count  # no pixel listed twice
    return count, mask


def must_trace(outputs, scene) -> tuple[np.ndarray, np.ndarray]:
    """(pixels that need a ray whatever the maps say: their surface reflects or refracts, or they
    border another instance or the sky; sky pixels away from any border)."""
    from rgraph.scene.build import load_scene_data

    data = load_scene_data(scene, (SIZE, SIZE))
    inst, _prim = decode_visibility(outputs["visibility"][..., 0], prim_bits(data))
    mask = needs_secondary_rays(data.materials)[instance_materials(data)]
    classified = np.where(inst >= 0, mask[np.maximum(inst, 0)], 0).astype(bool)
    padded = np.pad(inst, 1, mode="edge")  # hybrid.glsl clamps the neighbours to the image
    boundary = np.zeros(inst.shape, dtype=bool)
    for dy, dx in ((0, 1), (2, 1), (1, 0), (1, 2)):
        boundary |= padded[dy:dy + SIZE, dx:dx + SIZE] != inst
    return classified | boundary, (inst < 0) & ~boundary


@pytest.mark.vulkan
@pytest.mark.parametrize("scene, wavefront", [(TIR, "0"), (TINY, "0"), (TIR, "1")],
                         ids=["wave_tir", "rt_tiny", "wave_tir-by-levels"])
def test_compute_pass_lists_only_what_needs_rays_and_keeps_the_image(scene, wavefront):
    params = {"rt.wavefront": wavefront}  # 1: the listed pixels' trees traced level by level
    first = _run(FIRST, scene, params, extra=("first_args", "first_list", "visibility"))
    every = _run("rt_hybrid", scene, params)
    count, listed = listed_pixels(first)
    needed, open_sky = must_trace(first, scene)
    assert listed[needed].all()  # every pixel that needs a ray is traced
    assert not listed[open_sky].any()  # the sky alone is never traced
    finished = ~listed & ~open_sky
    assert finished.sum() > 0.1 * SIZE * SIZE  # surfaces shaded without a ray: the maps decided
    assert 0 < count < SIZE * SIZE
    a, b = _image(every), _image(first)
    assert np.isfinite(b).all()
    assert np.abs(a - b).max() <= 1e-3  # the same shading code in a compute shader


@pytest.mark.vulkan
def test_without_light_maps_every_lit_surface_is_traced():
    """``rt.light_maps: 0``: no shadow test can be decided without a ray, so every surface the
    lights reach is listed, and the image is still the every-pixel one."""
    first = _run(FIRST, TIR, params={"rt.light_maps": "0"}, extra=("first_args", "first_list", "visibility"))
    every = _run("rt_hybrid", TIR, params={"rt.light_maps": "0"})
    _count, listed = listed_pixels(first)
    mapped = _run(FIRST, TIR, extra=("first_args", "first_list", "visibility"))
    _count, listed_mapped = listed_pixels(mapped)
    assert listed.sum() > listed_mapped.sum()  # the maps take pixels off the list
    assert listed[listed_mapped].all()
    assert np.abs(_image(every) - _image(first)).max() <= 1e-3
