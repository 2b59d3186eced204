"""NumPy float64 references of the three HBAO passes (``passes/hbao.py``); no Vulkan.

The AO working resolution is ``hbao.scale`` (0.25 by default: quarter resolution; any
``1 / k`` with an integer reduction factor ``k``, 1 included: full resolution). "Quarter"
below means "working resolution"; ``k x k`` blocks are 4x4 at the default.

1. ``downsample``: each quarter texel takes the NEAREST surface of its k x k block, i.e. the
   smallest view distance, which with reversed-Z is the LARGEST stored depth value. This is
   the conservative choice for AO: no occluder disappears at quarter resolution (a 1-3 px
   instrument shaft still occludes what is behind it) and sky (depth 0) only survives
   where the whole block is sky, so sky never erases geometry at silhouettes. The
   background side of a silhouette is then recovered by the depth-aware upsample, which
   rejects the foreground quarter depth for background pixels.
2. ``hbao``: horizon-based AO (Bavoil and Sainz 2008) on the quarter depth: per pixel,
   ``directions`` screen directions (rotated per pixel by a 4x4 Bayer pattern), ``steps``
   texel-snapped samples each within ``radius`` (world units, projected to quarter pixels,
   at most ``max_radius_px`` FULL-resolution pixels, i.e. ``max_radius_px * scale`` quarter
   pixels, so every scale approximates the same screen-space footprint); along each direction the horizon angle, measured from the
   tangent plane (``sin h = N.V / |V|``), starts at ``angle_bias`` and every sample that
   raises it adds ``W(r) (sin h_new - sin h_old)`` with ``W(r) = 1 - r^2 / R^2``
   (horizon integration of the paper; measuring elevation from the tangent plane rather
   than the eye-space xy plane keeps texel snapping from self-occluding flat surfaces).
   AO = 1 - strength * mean over directions, clamped to [0, 1]. Sky pixels are 1 (no
   occlusion); sky samples never occlude. ``N = normalize(dP/dy x dP/dx)``, flipped when
   ``N.P > 0`` (P the view position) so that it faces the camera, also on walls seen
   edge-on, from the quarter depth: per axis, the neighbour difference with the smaller
   |dz|, ignoring sky and out-of-image neighbours.
3. ``upsample``: joint bilateral upsample: the 2x2 nearest quarter texels (the bilinear
   footprint, clamped to the image) weighted by bilinear weight times
   ``exp(-sharpness * (rel_i - min rel))`` with ``rel = |z_full - z_quarter| / z_full``
   (view distances), so the best-matching texel keeps its bilinear weight and texels across
   a depth edge vanish; sky quarter texels get weight 0; full-res sky pixels are 1.
   At k = 1 the footprint is the pixel itself with bilinear weight 1 (the others 0) and
   the same depth, so the upsample is the identity; the downsample is a copy.

The reference setting of ``rgraph sweep`` (the truth the knobs approximate):
``hbao.scale=1 hbao.directions=32 hbao.steps=32``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .screenspace_ref import Camera, linear_depth, view_position

BAYER4 = np.array([[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]], dtype=np.float64) / 16.0


@dataclass(frozen=True)
class HBAOSettings:
    directions: int = 8
    steps: int = 4
    radius: float = 0.02          # world units (metres)
    angle_bias: float = 0.3       # radians added to the tangent elevation
    strength: float = 1.0
    max_radius_px: float = 128.0  # full-resolution pixels (32 quarter pixels at scale 0.25)
    upsample_sharpness: float = 32.0
    scale: float = 0.25           # working resolution: 1 / factor, factor a positive integer

    @classmethod
    def from_params(cls, params: dict) -> HBAOSettings:
        d = cls()
        return cls(directions=int(params.get("hbao.directions", d.directions)),
                   steps=int(params.get("hbao.steps", d.steps)),
                   radius=float(params.get("hbao.radius", d.radius)),
                   angle_bias=float(params.get("hbao.angle_bias", d.angle_bias)),
                   strength=float(params.get("hbao.strength", d.strength)),
                   max_radius_px=float(params.get("hbao.max_radius_px", d.max_radius_px)),
                   upsample_sharpness=float(params.get("hbao.upsample_sharpness", d.upsample_sharpness)),
                   scale=float(params.get("hbao.scale", d.scale)))

    @property
    def factor(self) -> int:
        """The integer reduction factor ``k = 1 / scale``."""
        return reduction_factor(self.scale)


def reduction_factor(scale: float) -> int:
    """``1 / scale`` as a positive integer; ValueError when it is not one."""
    if not 0 < scale <= 1:
        raise ValueError(f"hbao.scale must be in (0, 1], got {scale}")
    k = round(1.0 / scale)
    if abs(1.0 / scale - k) > 1e-6 * k:
        raise ValueError(f"hbao.scale must be 1 / k for an integer k (1, 0.5, 0.25, ...), got {scale}")
    return k


def quarter_extent(width: int, height: int, scale: float = 0.25) -> tuple[int, int]:
    """The working size the graph's ``{scale: s}`` gives (floor, at least 1)."""
    return max(1, int(width * scale)), max(1, int(height * scale))


def downsample(depth: np.ndarray, qsize: tuple[int, int], factor: int = 4) -> np.ndarray:
    """(qh, qw) nearest-surface (max reversed-Z) depth of each ``factor`` x ``factor`` block
    (clamped to the image); a copy at factor 1."""
    h, w = depth.shape[:2]
    d = np.asarray(depth, np.float64).reshape(h, w)
    qw, qh = qsize
    k = factor
    out = np.zeros((qh, qw))
    for j in range(qh):
        for i in range(qw):
            y0, x0 = min(k * j, h - 1), min(k * i, w - 1)
            out[j, i] = d[y0:min(k * j + k, h), x0:min(k * i + k, w)].max()
    return out


def _quarter_pos(dq: np.ndarray, i: int, j: int, cam: Camera) -> np.ndarray:
    qh, qw = dq.shape
    return view_position(dq[j, i], np.array([(i + 0.5) / qw, (j + 0.5) / qh]), cam)


def _derivatives(dq: np.ndarray, i: int, j: int, p: np.ndarray, cam: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Position change per quarter texel along screen x and y (y down)."""
    qh, qw = dq.shape

    def axis(dx: int, dy: int, fallback: np.ndarray) -> np.ndarray:
        best = None
        for sign in (1, -1):
            x, y = i + sign * dx, j + sign * dy
            if 0 <= x < qw and 0 <= y < qh and dq[y, x] > 0:
                diff = (_quarter_pos(dq, x, y, cam) - p) * sign
                if best is None or abs(diff[2]) < abs(best[2]):
                    best = diff
        return fallback if best is None else best

    return axis(1, 0, np.array([1.0, 0.0, 0.0])), axis(0, 1, np.array([0.0, -1.0, 0.0]))


def hbao(dq: np.ndarray, cam: Camera, s: HBAOSettings) -> np.ndarray:
    """(qh, qw) ambient visibility in [0, 1] (1 = unoccluded) from quarter depth ``dq``."""
    dq = np.asarray(dq, np.float64)
    qh, qw = dq.shape
    out = np.ones((qh, qw))
    r2max = s.radius * s.radius
    px_per_ndc = cam.p00 * qw / 2.0
    sin_bias = math.sin(s.angle_bias)
    for j in range(qh):
        for i in range(qw):
            if dq[j, i] <= 0:
                continue
            p = _quarter_pos(dq, i, j, cam)
            ddx, ddy = _derivatives(dq, i, j, p, cam)
            n = np.cross(ddy, ddx)
            length = float(np.linalg.norm(n))
            n = np.array([0.0, 0.0, 1.0]) if length < 1e-30 else n / length
            n = -n if float(n @ p) > 0 else n  # face the camera (V = -p), also for walls seen edge-on
            radius_px = min(s.radius * px_per_ndc / -p[2], s.max_radius_px * s.scale)
            step = max(radius_px / (s.steps + 1), 1.0)
            rot, jitter = BAYER4[j % 4, i % 4], BAYER4[(j + 2) % 4, (i + 1) % 4]
            total = 0.0
            for k in range(s.directions):
                theta = 2.0 * math.pi * (k + rot) / s.directions
                dx, dy = math.cos(theta), math.sin(theta)
                sin_h = sin_bias
                ray = jitter * step + 1.0
                acc = 0.0
                for _ in range(s.steps):
                    x = math.floor(i + 0.5 + ray * dx)
                    y = math.floor(j + 0.5 + ray * dy)
                    ray += step
                    if not (0 <= x < qw and 0 <= y < qh):
                        break
                    if dq[y, x] <= 0:
                        continue
                    v = _quarter_pos(dq, x, y, cam) - p
                    r2 = float(v @ v)
                    if r2 >= r2max or r2 < 1e-20:
                        continue
                    sin_s = float(n @ v) / math.sqrt(r2)
                    if sin_s > sin_h:
                        acc += (1.0 - r2 / r2max) * (sin_s - sin_h)
                        sin_h = sin_s
                total += acc
            out[j, i] = min(max(1.0 - s.strength * total / s.directions, 0.0), 1.0)
    return out


def upsample(ao_q: np.ndarray, dq: np.ndarray, depth: np.ndarray, cam: Camera, sharpness: float) -> np.ndarray:
    """(h, w) joint-bilateral upsample of quarter AO guided by full-res depth."""
    ao_q = np.asarray(ao_q, np.float64).reshape(dq.shape)
    d = np.asarray(depth, np.float64).reshape(np.shape(depth)[:2])
    h, w = d.shape
    qh, qw = dq.shape
    zq = linear_depth(dq, cam.near)
    out = np.ones((h, w))
    for y in range(h):
        for x in range(w):
            if d[y, x] <= 0:
                continue
            zf = cam.near / d[y, x]
            fx, fy = (x + 0.5) * qw / w - 0.5, (y + 0.5) * qh / h - 0.5
            bx, by = math.floor(fx), math.floor(fy)
            ax, ay = fx - bx, fy - by
            taps = []
            for oy, wy in ((0, 1 - ay), (1, ay)):
                for ox, wx in ((0, 1 - ax), (1, ax)):
                    tx, ty = min(max(bx + ox, 0), qw - 1), min(max(by + oy, 0), qh - 1)
                    if dq[ty, tx] > 0:
                        taps.append((wx * wy, abs(zf - zq[ty, tx]) / zf, ao_q[ty, tx]))
            if not taps:
                continue
            rel_min = min(t[1] for t in taps)
            ws = [wb * math.exp(-sharpness * (rel - rel_min)) for wb, rel, _ in taps]
            out[y, x] = sum(wi * t[2] for wi, t in zip(ws, taps, strict=True)) / sum(ws)
    return out


def bilinear_upsample(ao_q: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Plain bilinear upsample (clamp to edge): what the bilateral upsample must beat at edges."""
    ao_q = np.asarray(ao_q, np.float64)
    qh, qw = ao_q.shape[:2]
    w, h = size
    fx = (np.arange(w) + 0.5) * qw / w - 0.5
    fy = (np.arange(h) + 0.5) * qh / h - 0.5
    bx, by = np.floor(fx).astype(int), np.floor(fy).astype(int)
    ax, ay = fx - bx, fy - by
    x0, x1 = np.clip(bx, 0, qw - 1), np.clip(bx + 1, 0, qw - 1)
    y0, y1 = np.clip(by, 0, qh - 1), np.clip(by + 1, 0, qh - 1)
    top = ao_q[y0][:, x0] * (1 - ax) + ao_q[y0][:, x1] * ax
    bot = ao_q[y1][:, x0] * (1 - ax) + ao_q[y1][:, x1] * ax
    return top * (1 - ay)[:, None] + bot * ay[:, None]


def reference(depth: np.ndarray, cam: Camera, s: HBAOSettings) -> dict[str, np.ndarray]:
    """All three stages: ``depth_quarter``, ``ao_quarter`` and ``ao`` from full-res ``depth``."""
    h, w = np.shape(depth)[:2]
    dq = downsample(depth, quarter_extent(w, h, s.scale), s.factor)
    ao_q = hbao(dq, cam, s)
    return {"depth_quarter": dq, "ao_quarter": ao_q, "ao": upsample(ao_q, dq, depth, cam, s.upsample_sharpness)}
