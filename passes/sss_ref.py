"""NumPy float64 reference of separable screen-space subsurface scattering (``passes/sss.py``).

Jimenez, Zsolnai, Jarabo, Freude, Auzinger, Wu, von der Pahlen, Wimmer, Gutierrez 2015,
"Separable Subsurface Scattering" (and its SeparableSSS reference code):

- ``kernel(samples, strength, falloff)``: the skin diffusion profile as a sum of five
  Gaussians (variances 0.0484, 0.187, 0.567, 1.99, 7.41; weights 0.100, 0.118, 0.113,
  0.358, 0.078; per-channel ``falloff`` widens each channel), sampled at ``samples`` offsets
  in [-R, R] (R = 3 for more than 20 samples, else 2) spaced quadratically (denser near 0),
  each weighted by its profile value times the offset interval it covers; the centre tap is
  moved first, weights are normalized to sum 1 per channel, then blended with the identity
  by ``strength`` (``k0 = 1 - s + s k0``, ``ki = s ki``), so every channel still sums to 1.
- ``blur(color, depth, sss, ...)``: one direction. Per pixel with SSS strength ``a > 0``
  (``normal_sss.a``) and geometry (depth > 0): the world-space width ``width * a`` is
  projected to pixels at the pixel's view distance z (``width * a * P / z * size / 2``, P
  the projection scale along the direction) and divided by 3 (the kernel range, as in the
  paper); tap i samples the colour bilinearly (clamp to edge) at ``centre + w_i * step``
  and the depth at the nearest texel there; follow-surface: the tap's colour is lerped
  toward the centre colour by ``saturate(|z_centre - z_tap| / follow_depth)`` (sky taps:
  fully). Output rgb = sum of kernel weight * tap colour; alpha = the centre's alpha.
  Pixels with ``a == 0``, ``width == 0`` or sky are copied unchanged (exact identity).

``sss.kernel = 2d`` (the reference setting of ``rgraph sweep``): the NON-separable 2D
convolution with the same diffusion profile, which the separable pair approximates.
``kernel_2d``: the tensor grid of the same ``samples`` quadratic offsets on both axes,
restricted to the disc ``r <= R`` (so the support is rotationally symmetric); tap (i, j)
weighs ``profile(sqrt(ox^2 + oy^2)) * cell_i * cell_j`` (cell = the offset interval of the
1D kernel: a midpoint quadrature of the 2D integral over the grid's non-uniform cells);
weights normalized to 1 per channel, then blended with the identity by ``strength`` once.
The separable pair instead applies ``k(x) k(y)`` (and the strength blend twice), which
equals the radial profile only for a single Gaussian: for the five-Gaussian skin profile
it is too dark along the diagonals and too bright along the axes (a "plus"-shaped
kernel). ``blur_2d``: like ``blur`` but tap ``(ox, oy)`` samples at
``centre + (ox * step_x, oy * step_y)`` with the per-axis projected steps. In the graph,
``sss_blur_h`` does the whole 2D blur into ``sss_tmp`` and ``sss_blur_v`` copies it to
``diffuse`` unchanged, so the passes, their resources and their synchronization are the
same in both modes. Cost: 85 / 225 / 513 taps per pixel at 11 / 17 / 25 samples instead
of 2 * samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .screenspace_ref import linear_depth

PROFILE = ((0.100, 0.0484), (0.118, 0.187), (0.113, 0.567), (0.358, 1.99), (0.078, 7.41))
SKIN_STRENGTH = (0.48, 0.41, 0.28)
SKIN_FALLOFF = (1.0, 0.37, 0.3)
SAMPLE_COUNTS = (11, 17, 25)
KERNELS = ("separable", "2d")


@dataclass(frozen=True)
class SSSSettings:
    samples: int = 17
    width: float = 0.01         # world units covered by the kernel's [-3, 3] at SSS strength 1
    follow_depth: float = 0.004  # world-space depth difference at which a tap is fully rejected
    strength: tuple[float, float, float] = SKIN_STRENGTH
    falloff: tuple[float, float, float] = SKIN_FALLOFF
    kernel: str = "separable"   # or "2d": the non-separable reference

    @classmethod
    def from_params(cls, params: dict) -> SSSSettings:
        d = cls()
        samples = int(params.get("sss.samples", d.samples))
        if samples not in SAMPLE_COUNTS:
            raise ValueError(f"sss.samples must be one of {SAMPLE_COUNTS}, not {samples}")
        kernel_kind = str(params.get("sss.kernel", d.kernel))
        if kernel_kind not in KERNELS:
            raise ValueError(f"sss.kernel must be one of {KERNELS}, not {kernel_kind!r}")
        return cls(samples=samples, width=float(params.get("sss.width", d.width)),
                   follow_depth=float(params.get("sss.follow_depth", d.follow_depth)), kernel=kernel_kind)


def _gaussian(variance: float, r: float, falloff: tuple[float, float, float]) -> np.ndarray:
    rr = r / (0.001 + np.asarray(falloff, np.float64))
    return np.exp(-(rr * rr) / (2.0 * variance)) / (2.0 * math.pi * variance)


def profile(r: float, falloff: tuple[float, float, float] = SKIN_FALLOFF) -> np.ndarray:
    """The sum-of-Gaussians skin diffusion profile at distance r (per channel)."""
    return sum(w * _gaussian(v, r, falloff) for w, v in PROFILE)


def kernel_range(samples: int) -> float:
    """R: the kernel covers offsets [-R, R] (in units of the projected width / 3)."""
    return 3.0 if samples > 20 else 2.0


def _offsets_and_cells(samples: int) -> tuple[np.ndarray, np.ndarray]:
    """The quadratic 1D offsets in [-R, R] and the interval each covers."""
    if samples < 3 or samples % 2 == 0:
        raise ValueError("the SSS kernel needs an odd sample count >= 3")
    rng = kernel_range(samples)
    step = 2.0 * rng / (samples - 1)
    o = -rng + np.arange(samples) * step
    offsets = rng * np.sign(o) * np.abs(o) ** 2 / rng ** 2
    cells = np.zeros(samples)
    for i in range(samples):
        w0 = abs(offsets[i] - offsets[i - 1]) if i > 0 else 0.0
        w1 = abs(offsets[i] - offsets[i + 1]) if i < samples - 1 else 0.0
        cells[i] = (w0 + w1) / 2.0
    return offsets, cells


def kernel(samples: int, strength: tuple[float, float, float] = SKIN_STRENGTH,
           falloff: tuple[float, float, float] = SKIN_FALLOFF) -> np.ndarray:
    """(samples, 4): rgb weights and offset (in [-R, R]); the centre tap first."""
    offsets, cells = _offsets_and_cells(samples)
    k = np.zeros((samples, 4))
    k[:, 3] = offsets
    for i in range(samples):
        k[i, :3] = cells[i] * profile(offsets[i], falloff)
    k = np.concatenate([k[samples // 2: samples // 2 + 1], k[: samples // 2], k[samples // 2 + 1:]])
    k[:, :3] /= k[:, :3].sum(axis=0)
    s = np.asarray(strength, np.float64)
    k[0, :3] = (1.0 - s) + s * k[0, :3]
    k[1:, :3] *= s
    return k


def kernel_2d(samples: int, strength: tuple[float, float, float] = SKIN_STRENGTH,
              falloff: tuple[float, float, float] = SKIN_FALLOFF) -> np.ndarray:
    """(taps, 5): rgb weights and offsets (ox, oy) of the non-separable 2D kernel on the disc
    ``r <= R`` of the (samples x samples) offset grid; the centre tap first."""
    offsets, cells = _offsets_and_cells(samples)
    rng = kernel_range(samples)
    rows = []
    centre = samples // 2
    order = [(centre, centre)] + [(j, i) for j in range(samples) for i in range(samples) if (j, i) != (centre, centre)]
    for j, i in order:
        r = math.hypot(offsets[i], offsets[j])
        if r > rng * (1.0 + 1e-12):
            continue
        rows.append([*(cells[i] * cells[j] * profile(r, falloff)), offsets[i], offsets[j]])
    k = np.array(rows)
    k[:, :3] /= k[:, :3].sum(axis=0)
    s = np.asarray(strength, np.float64)
    k[0, :3] = (1.0 - s) + s * k[0, :3]
    k[1:, :3] *= s
    return k


def _bilinear(img: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Sample (h, w, c) at continuous pixel coordinates (pixel centres at .5), clamp to edge."""
    h, w = img.shape[:2]
    fx, fy = px - 0.5, py - 0.5
    x0, y0 = np.floor(fx).astype(int), np.floor(fy).astype(int)
    ax, ay = (fx - x0)[..., None], (fy - y0)[..., None]

    def at(x, y):
        return img[np.clip(y, 0, h - 1), np.clip(x, 0, w - 1)]

    return ((at(x0, y0) * (1 - ax) + at(x0 + 1, y0) * ax) * (1 - ay)
            + (at(x0, y0 + 1) * (1 - ax) + at(x0 + 1, y0 + 1) * ax) * ay)


def blur(color: np.ndarray, depth: np.ndarray, sss: np.ndarray, *, direction: str, p00: float, p11: float,
         near: float, settings: SSSSettings, kern: np.ndarray | None = None) -> np.ndarray:
    """One separable pass (``direction`` "h" or "v") over (h, w, 4) ``color``; see the module doc."""
    color = np.asarray(color, np.float64)
    d = np.asarray(depth, np.float64).reshape(color.shape[:2])
    a = np.asarray(sss, np.float64).reshape(color.shape[:2])
    k = kernel(settings.samples, settings.strength, settings.falloff) if kern is None else kern
    h, w = d.shape
    z = linear_depth(d, near)
    active = (a > 0) & (d > 0) & (settings.width > 0)
    scale, size = (abs(p00), w) if direction == "h" else (abs(p11), h)
    with np.errstate(divide="ignore", invalid="ignore"):
        step = np.where(active, settings.width * a * scale / z * size / 2.0 / 3.0, 0.0)
    offsets = [(k[i, 3] * step, 0.0) if direction == "h" else (0.0, k[i, 3] * step) for i in range(1, len(k))]
    return _follow_surface_sum(color, z, active, k[:, :3], offsets, settings.follow_depth)


def blur_2d(color: np.ndarray, depth: np.ndarray, sss: np.ndarray, *, p00: float, p11: float, near: float,
            settings: SSSSettings, kern: np.ndarray | None = None) -> np.ndarray:
    """The non-separable 2D blur (``sss.kernel = 2d``) over (h, w, 4) ``color``; see the module doc."""
    color = np.asarray(color, np.float64)
    d = np.asarray(depth, np.float64).reshape(color.shape[:2])
    a = np.asarray(sss, np.float64).reshape(color.shape[:2])
    k = kernel_2d(settings.samples, settings.strength, settings.falloff) if kern is None else kern
    h, w = d.shape
    z = linear_depth(d, near)
    active = (a > 0) & (d > 0) & (settings.width > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        base = np.where(active, settings.width * a / z / 2.0 / 3.0, 0.0)
    step_x, step_y = base * abs(p00) * w, base * abs(p11) * h
    offsets = [(k[i, 3] * step_x, k[i, 4] * step_y) for i in range(1, len(k))]
    return _follow_surface_sum(color, z, active, k[:, :3], offsets, settings.follow_depth)


def _follow_surface_sum(color: np.ndarray, z: np.ndarray, active: np.ndarray, weights: np.ndarray,
                        offsets: list[tuple], follow_depth: float) -> np.ndarray:
    """Sum of ``weights[0]`` x centre and ``weights[i]`` x the bilinear tap at pixel centre +
    ``offsets[i-1]`` (per-pixel arrays or scalars), each tap pulled toward the centre colour by
    its linear-depth difference / ``follow_depth``; inactive pixels keep ``color``."""
    h, w = z.shape
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
    cx, cy = xs + 0.5, ys + 0.5
    out = color.copy()
    acc = color[..., :3] * weights[0]
    for weight, (dx, dy) in zip(weights[1:], offsets, strict=True):
        px, py = cx + dx, cy + dy
        tap = _bilinear(color[..., :3], px, py)
        tx = np.clip(np.floor(px).astype(int), 0, w - 1)
        ty = np.clip(np.floor(py).astype(int), 0, h - 1)
        with np.errstate(invalid="ignore"):
            s = np.clip(np.abs(z - z[ty, tx]) / follow_depth, 0.0, 1.0)
        s = np.where(np.isfinite(s), s, 1.0)[..., None]
        tap = tap + (color[..., :3] - tap) * s
        acc = acc + weight * tap
    out[..., :3] = np.where(active[..., None], acc, color[..., :3])
    return out


def reference(color: np.ndarray, depth: np.ndarray, sss: np.ndarray, *, p00: float, p11: float, near: float,
              settings: SSSSettings) -> dict[str, np.ndarray]:
    """Both passes: ``sss_tmp`` (horizontal, or the whole 2D blur) and the final ``diffuse``
    (vertical over sss_tmp, or a copy of it)."""
    kw = dict(p00=p00, p11=p11, near=near, settings=settings)
    if settings.kernel == "2d":
        tmp = blur_2d(color, depth, sss, **kw)
        return {"sss_tmp": tmp, "diffuse": tmp.copy()}
    tmp = blur(color, depth, sss, direction="h", **kw)
    return {"sss_tmp": tmp, "diffuse": blur(tmp, depth, sss, direction="v", **kw)}
