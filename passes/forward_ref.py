"""NumPy float64 reference of the forward BRDF (``shaders/forward/brdf.glsl``); no Vulkan needed.

Every function mirrors the GLSL function of the same name, constant for constant, and works
on arrays (leading axes broadcast). ``shade_case`` is what the BRDF test pass computes per
pixel: one light plus the split-sum IBL terms, clamped like the forward pass's outputs.
"""

from __future__ import annotations

import numpy as np

MIN_ROUGHNESS = 0.045
MIN_N_DOT_V = 1e-4
HDR_MAX = 60000.0
NORMALIZE_EPS2 = 1e-20


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(np.asarray(a) * np.asarray(b), axis=-1)


def safe_normalize(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    len2 = _dot(v, v)[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = v / np.sqrt(len2)
    return np.where(len2 > NORMALIZE_EPS2, unit, np.broadcast_to(fallback, v.shape))


def ggx_alpha(perceptual_roughness: np.ndarray | float) -> np.ndarray:
    r = np.clip(np.asarray(perceptual_roughness, dtype=np.float64), MIN_ROUGHNESS, 1.0)
    return r * r


def d_ggx(noh: np.ndarray, one_minus_noh2: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    a = noh * alpha
    k = alpha / np.maximum(one_minus_noh2 + a * a, alpha * alpha)
    return k * k / np.pi


def v_smith_ggx_correlated(nov: np.ndarray, nol: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    a2 = np.asarray(alpha) ** 2
    gv = nol * np.sqrt(nov * nov * (1.0 - a2) + a2)
    gl = nov * np.sqrt(nol * nol * (1.0 - a2) + a2)
    return 0.5 / np.maximum(gv + gl, 1e-12)


def f_schlick(f0: np.ndarray, voh: np.ndarray) -> np.ndarray:
    return f0 + (1.0 - f0) * ((1.0 - voh) ** 5)[..., None]


def specular_occlusion(nov: np.ndarray, ao: np.ndarray, perceptual_roughness: np.ndarray) -> np.ndarray:
    r = np.clip(perceptual_roughness, MIN_ROUGHNESS, 1.0)
    return np.clip((nov + ao) ** np.exp2(-16.0 * r - 1.0) - 1.0 + ao, 0.0, 1.0)


def combine_ao(screen_ao: np.ndarray, baked_ao: np.ndarray, mode: int = 0) -> np.ndarray:
    """AO_COMBINE: 0 = min (default), 1 = max, 2 = multiply."""
    fn = {0: np.minimum, 1: np.maximum, 2: np.multiply}[mode]
    return np.clip(fn(screen_ao, baked_ao), 0.0, 1.0)


def make_surface(normal, to_view, fallback_normal, base_color, roughness, metallic) -> dict[str, np.ndarray]:
    v = safe_normalize(to_view, np.array([0.0, 0.0, 1.0]))
    n = safe_normalize(normal, safe_normalize(fallback_normal, v))
    nov = np.clip(_dot(n, v), MIN_N_DOT_V, 1.0)
    m = np.clip(np.asarray(metallic, dtype=np.float64), 0.0, 1.0)[..., None]
    base = np.clip(np.asarray(base_color, dtype=np.float64), 0.0, 1.0)
    r = np.clip(np.asarray(roughness, dtype=np.float64), MIN_ROUGHNESS, 1.0)
    return {"n": n, "v": v, "nov": nov, "diffuse_color": base * (1.0 - m), "f0": 0.04 * (1.0 - m) + base * m,
            "roughness": r, "alpha": r * r}


def eval_light(s: dict[str, np.ndarray], ldir: np.ndarray, radiance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(diffuse, specular) reflected radiance of one light; zero where N.L <= 0."""
    nol_raw = _dot(s["n"], ldir)
    lit = nol_raw > 0.0
    nol = np.where(lit, np.minimum(nol_raw, 1.0), 0.0)
    h = safe_normalize(s["v"] + ldir, s["n"])
    noh = np.clip(_dot(s["n"], h), 0.0, 1.0)
    nxh = np.cross(s["n"], h)
    voh = np.clip(_dot(s["v"], h), 0.0, 1.0)
    d = d_ggx(noh, _dot(nxh, nxh), s["alpha"])
    vis = v_smith_ggx_correlated(s["nov"], np.where(lit, nol, 1.0), s["alpha"])
    f = f_schlick(s["f0"], voh)
    spec = (d * vis * nol)[..., None] * f * radiance
    diff = s["diffuse_color"] * (nol / np.pi)[..., None] * radiance
    return np.where(lit[..., None], diff, 0.0), np.where(lit[..., None], spec, 0.0)


def eval_ibl(s: dict[str, np.ndarray], lut: np.ndarray, prefiltered: np.ndarray, irradiance: np.ndarray,
             ao: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    diff = s["diffuse_color"] * irradiance * ao[..., None]
    so = specular_occlusion(s["nov"], ao, s["roughness"])
    spec = prefiltered * (s["f0"] * lut[..., 0:1] + lut[..., 1:2]) * so[..., None]
    return diff, spec


def hdr_clamp(c: np.ndarray) -> np.ndarray:
    return np.clip(c, 0.0, HDR_MAX)


#: Layout of one BRDF test case: 8 vec4 (128 bytes), see shaders/forward/brdf_test.frag.
CASE_FIELDS = ("normal", "to_view", "to_light", "radiance", "base_color", "material", "prefiltered", "irradiance")


def pack_cases(cases: dict[str, np.ndarray]) -> np.ndarray:
    """(n, 8, 4) float32 case records from per-field arrays.

    ``normal``/``to_view``/``to_light``/``radiance``/``base_color``/``prefiltered`` are (n, 3);
    ``irradiance`` (n, 3) with the LUT's (A, B) in ``lut`` (n, 2) stored in the last two
    slots of ``fallback`` -- see brdf_test.frag for the exact placement.
    """
    n = len(cases["normal"])
    rec = np.zeros((n, 8, 4), dtype=np.float32)
    rec[:, 0, :3] = cases["normal"]
    rec[:, 1, :3] = cases["to_view"]
    rec[:, 2, :3] = cases["to_light"]
    rec[:, 3, :3] = cases["radiance"]
    rec[:, 4, :3] = cases["base_color"]
    rec[:, 5] = np.stack([cases["roughness"], cases["metallic"], cases["screen_ao"], cases["baked_ao"]], axis=-1)
    rec[:, 6, :3] = cases["prefiltered"]
    rec[:, 7, :3] = cases["irradiance"]
    rec[:, 0, 3] = cases["lut"][:, 0]
    rec[:, 1, 3] = cases["lut"][:, 1]
    rec[:, 2, 3] = 0.0
    rec[:, 4, 3] = 0.0
    return rec


def shade_case(rec: np.ndarray, fallback_normal: np.ndarray | None = None, ao_mode: int = 0
               ) -> tuple[np.ndarray, np.ndarray]:
    """What brdf_test.frag writes for case records ``rec`` (n, 8, 4): (diffuse, specular) (n, 3).

    The records are taken as the float32 values the GPU reads, then computed in float64.
    ``fallback_normal`` is the geometric normal used when the shading normal is zero
    (the test pass uses the record's to_view direction, as a camera-facing surface).
    """
    r = rec.astype(np.float64)
    n, v, ldir = r[:, 0, :3], r[:, 1, :3], r[:, 2, :3]
    fallback = v if fallback_normal is None else fallback_normal
    s = make_surface(n, v, fallback, r[:, 4, :3], r[:, 5, 0], r[:, 5, 1])
    l_unit = safe_normalize(ldir, s["n"])
    diff, spec = eval_light(s, l_unit, r[:, 3, :3])
    ao = combine_ao(r[:, 5, 2], r[:, 5, 3], ao_mode)
    lut = np.stack([r[:, 0, 3], r[:, 1, 3]], axis=-1)
    di, si = eval_ibl(s, lut, r[:, 6, :3], r[:, 7, :3], ao)
    return hdr_clamp(diff + di), hdr_clamp(spec + si)
