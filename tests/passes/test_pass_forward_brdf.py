"""FORWARD_TEST: the shipped BRDF GLSL (shaders/forward/brdf.glsl) on a grid of hard and random
cases, on lavapipe, vs the NumPy float64 reference (passes/forward_ref.shade_case).

Hard cases: roughness 0 (clamped to MIN_ROUGHNESS: finite peak), N.V -> 0 and slightly
negative (interpolated normals), zero normals (fallback), zero light/view vectors, lights
below the horizon, V = -L (half vector undefined), metallic and dielectric, every AO combine
mode. The forward pass builds no tangent frame (no normal maps), so there is none to degenerate.

Tolerance: |gpu - ref| <= 2e-3 * |ref| + 1e-4 (float32 arithmetic vs float64; the steepest
case is the roughness-0 mirror peak, ~1e-4 relative).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from locations import TESTS
from rgraph.passes import forward_ref as ref

from rgraph.compiler.pipeline import compile_graph
from rgraph.impl import PassImpl, register

GRAPH = TESTS / "pass_graphs" / "forward_brdf.yaml"
WIDTH = 32
RTOL, ATOL = 2e-3, 1e-4


@register("forward_brdf_test")
class BrdfGrid(PassImpl):
    """Full-screen triangle; one case per pixel from the ``cases`` storage buffer."""

    def __init__(self, setup):
        super().__init__(setup)
        from rgraph.passes.forward import ao_combine_mode, color_locations

        from rgraph.vk.passkit import Binding

        loc = color_locations(setup, ("test_diffuse", "test_specular"))
        self.count = int(setup.buffer("cases", 0)[1]) // 128
        self.sets = setup.descriptors([Binding(0, "storage_buffer", "cases")])
        self.pipeline = setup.graphics_pipeline(
            "lib/fullscreen.vert", "forward/brdf_test.frag", [self.sets.layout], push_constant_bytes=8,
            defines={"LOC_DIFFUSE": loc["test_diffuse"], "LOC_SPECULAR": loc["test_specular"],
                     "AO_COMBINE": ao_combine_mode(setup)})
        self.width = setup.extent[0]

    def record(self, rec, frame_set):
        from rgraph.vk.passkit import pack

        rec.bind(self.pipeline, [self.sets[frame_set]])
        rec.push(self.pipeline, pack("2I", self.width, self.count))
        rec.draw(3)


def _unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def hard_cases() -> dict[str, np.ndarray]:
    """Structured grid: roughness x metallic x N.V x light placement, plus degenerate vectors."""
    rows = []
    n = np.array([0.0, 0.0, 1.0])
    roughness = [0.0, 1e-3, 0.045, 0.1, 0.3, 0.6, 1.0]
    metallic = [0.0, 1.0]
    novs = [1.0, 0.5, 0.05, 1e-3, 0.0, -0.01, -0.3]
    for r, m, nov in itertools.product(roughness, metallic, novs):
        v = np.array([np.sqrt(max(1 - nov * nov, 0.0)), 0.0, nov])
        mirror = 2 * nov * n - v
        for light in (mirror, n, _unit([-0.999, 0.0, 0.02]), _unit([0.3, 0.4, -0.5])):
            rows.append((n, v, light, r, m))
    # degenerate vectors: zero normal, zero view, zero light, V = -L, denormal-small normal
    v0 = _unit([0.2, 0.1, 1.0])
    for r, m in itertools.product([0.0, 0.5], [0.0, 1.0]):
        rows += [(np.zeros(3), v0, _unit([0.1, 0.3, 1.0]), r, m),
                 (np.zeros(3), v0, -v0, r, m),
                 (n, np.zeros(3), _unit([0.0, 0.6, 0.8]), r, m),
                 (n, v0, np.zeros(3), r, m),
                 (n, _unit([0.6, 0.0, 0.8]), _unit([-0.6, 0.0, -0.8]), r, m),
                 (np.array([1e-12, 0.0, 1e-12]), v0, v0, r, m),
                 (np.array([3.0, -2.0, 5.0]), v0 * 7.0, _unit([1.0, 1.0, 1.0]) * 0.01, r, m)]
    count = len(rows)
    rng = np.random.default_rng(11)
    return {
        "normal": np.array([r[0] for r in rows]), "to_view": np.array([r[1] for r in rows]),
        "to_light": np.array([r[2] for r in rows]), "roughness": np.array([r[3] for r in rows]),
        "metallic": np.array([r[4] for r in rows]),
        "radiance": np.tile([3.0, 2.5, 2.0], (count, 1)),
        "base_color": rng.uniform(0.05, 1.0, (count, 3)),
        "screen_ao": rng.uniform(0.0, 1.0, count), "baked_ao": rng.uniform(0.0, 1.0, count),
        "prefiltered": rng.uniform(0.0, 30.0, (count, 3)), "irradiance": rng.uniform(0.0, 2.0, (count, 3)),
        "lut": rng.uniform(0.0, 1.0, (count, 2)),
    }


def random_cases(count: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    normal = rng.normal(size=(count, 3))
    return {
        "normal": normal, "to_view": normal + rng.normal(size=(count, 3)) * 0.8,
        "to_light": normal + rng.normal(size=(count, 3)) * 0.8,
        "roughness": rng.uniform(0, 1, count), "metallic": rng.choice([0.0, 1.0, 0.3], count),
        "radiance": rng.uniform(0, 10, (count, 3)), "base_color": rng.uniform(0, 1, (count, 3)),
        "screen_ao": rng.uniform(0, 1, count), "baked_ao": rng.uniform(0, 1, count),
        "prefiltered": rng.uniform(0, 30, (count, 3)), "irradiance": rng.uniform(0, 2, (count, 3)),
        "lut": rng.uniform(0, 1, (count, 2)),
    }


def all_cases(total: int) -> np.ndarray:
    hard = ref.pack_cases(hard_cases())
    rest = ref.pack_cases(random_cases(total - len(hard), 5))
    return np.concatenate([hard, rest])


def run_grid(records: np.ndarray, ao_mode: int = 0):
    from rgraph.vk.executor import execute_plan

    height = len(records) // WIDTH
    plan = compile_graph(GRAPH, size=(WIDTH, height),
                         params={"cases": str(len(records)), "forward.ao_combine": str(ao_mode)})
    result = execute_plan(plan, validate=True, inputs={"cases": records.tobytes()}, read_outputs=True)
    diffuse = result.outputs["test_diffuse"].reshape(-1, 4)
    specular = result.outputs["test_specular"].reshape(-1, 4)
    return [m.text for m in result.messages], diffuse, specular


def test_reference_hard_cases_are_finite_and_bounded():
    records = ref.pack_cases(hard_cases())
    diffuse, specular = ref.shade_case(records)
    assert np.isfinite(diffuse).all() and np.isfinite(specular).all()
    assert diffuse.min() >= 0 and specular.max() <= ref.HDR_MAX
    # roughness 0 clamps to the minimum: same result as roughness MIN_ROUGHNESS
    a, b = records.copy(), records.copy()
    a[:, 5, 0], b[:, 5, 0] = 0.0, ref.MIN_ROUGHNESS
    b[:, 5, 0] = np.float32(ref.MIN_ROUGHNESS)  # what the GPU reads
    assert np.allclose(ref.shade_case(a)[1], ref.shade_case(b)[1], rtol=1e-5)  # r^-4: float32 0.045 is 4e-8 off


def test_reference_peak_and_energy():
    """The mirror peak at the minimum roughness equals F0 * D(1) * V * N.L * radiance in closed form."""
    alpha = ref.MIN_ROUGHNESS ** 2
    s = ref.make_surface(np.array([[0, 0, 1.0]]), np.array([[0, 0, 1.0]]), np.array([[0, 0, 1.0]]),
                         np.array([[1.0, 1.0, 1.0]]), 0.0, 1.0)
    _, spec = ref.eval_light(s, np.array([[0, 0, 1.0]]), np.array([1.0, 1.0, 1.0]))
    want = 1.0 / (np.pi * alpha * alpha) * 0.25  # D(1) * V(1, 1), V(1, 1) = 0.5 / (1 + 1)
    assert np.allclose(spec, want)
    # white furnace-ish: a rough dielectric's directional albedo (MC) stays below 1
    rng = np.random.default_rng(0)
    mu = rng.uniform(0, 1, 200000)
    phi = rng.uniform(0, 2 * np.pi, mu.size)
    ldirs = np.stack([np.sqrt(1 - mu * mu) * np.cos(phi), np.sqrt(1 - mu * mu) * np.sin(phi), mu], axis=-1)
    n = np.tile([0, 0, 1.0], (mu.size, 1))
    s = ref.make_surface(n, np.tile(_unit([0.5, 0, 0.8]), (mu.size, 1)), n, np.ones((mu.size, 3)), 0.5, 0.0)
    d, sp = ref.eval_light(s, ldirs, np.ones(3))
    albedo = (d + sp).mean(axis=0) * 2 * np.pi  # radiance 1 from every direction of the hemisphere
    assert np.all(albedo < 1.1) and np.all(albedo > 0.9)


@pytest.mark.vulkan
@pytest.mark.parametrize("ao_mode", [0, 1, 2])
def test_brdf_grid_matches_reference(ao_mode):
    records = all_cases(WIDTH * 24)
    messages, diffuse, specular = run_grid(records, ao_mode)
    assert messages == []
    assert np.isfinite(diffuse).all() and np.isfinite(specular).all()
    want_d, want_s = ref.shade_case(records, ao_mode=ao_mode)
    for name, got, want in (("diffuse", diffuse[:, :3], want_d), ("specular", specular[:, :3], want_s)):
        err = np.abs(got - want) - (RTOL * np.abs(want) + ATOL)
        worst = int(np.argmax(err))
        assert err.max() <= 0, (f"{name}: case {worst // 3} got {got.flat[worst]} want {want.flat[worst]}; "
                                f"record {records[worst // 3].tolist()}")
    assert np.all(diffuse[:, 3] == 1.0) and np.all(specular[:, 3] == 1.0)
    # the grid reaches the hard regimes: the roughness-0 mirror peak (metal: above 1e4)
    assert want_s.max() > 1e4
