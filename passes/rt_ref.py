"""NumPy float64 reference of ``rt_standalone``: a small CPU ray tracer of the same scene,
lighting model and ray tree (``passes.rt_model``). Brute force over every triangle: for tiny
test scenes only."""

from __future__ import annotations

import numpy as np

from .rt_model import MAX_STACK, Tables, primary_dir, sample_sky

T_MIN = 0.0
T_MAX = 1e30
EPS_DET = 1e-12


def offset_ray(p: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Wächter-Binder (Ray Tracing Gems ch. 6): move ``p`` off the surface along ``n`` by
    integer ULPs of its float32 bits (a fixed epsilon near the origin)."""
    origin, float_scale, int_scale = 1.0 / 32.0, 1.0 / 65536.0, 256.0
    p32 = np.asarray(p, dtype=np.float32)
    of_i = (int_scale * np.asarray(n, dtype=np.float64)).astype(np.int32)
    bits = p32.view(np.int32)
    moved = (bits + np.where(p32 < 0, -of_i, of_i)).astype(np.int32).view(np.float32).astype(np.float64)
    return np.where(np.abs(p) < origin, p + float_scale * n, moved)


def intersect(t: Tables, o: np.ndarray, d: np.ndarray, any_hit: bool = False):
    """Closest hit (t, triangle, u, v) of the ray, or None (Möller-Trumbore, both faces)."""
    v0, v1, v2 = t.triangles[:, 0], t.triangles[:, 1], t.triangles[:, 2]
    e1, e2 = v1 - v0, v2 - v0
    pv = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, pv)
    ok = np.abs(det) > EPS_DET
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tv = o - v0
    u = np.einsum("ij,ij->i", tv, pv) * inv
    qv = np.cross(tv, e1)
    v = (qv @ d) * inv
    dist = np.einsum("ij,ij->i", e2, qv) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (dist > T_MIN) & (dist < T_MAX)
    if not hit.any():
        return None
    idx = np.flatnonzero(hit)
    k = idx[np.argmin(dist[idx])]
    return float(dist[k]), int(k), float(u[k]), float(v[k])


def _normalize(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-20 and np.isfinite(n) else fallback


def _refract(d: np.ndarray, n: np.ndarray, eta: float) -> np.ndarray | None:
    cos_i = -float(d @ n)
    k = 1.0 - eta * eta * (1.0 - cos_i * cos_i)
    if k < 0.0:
        return None  # total internal reflection
    return eta * d + (eta * cos_i - np.sqrt(k)) * n


def shade_local(t: Tables, p: np.ndarray, ng: np.ndarray, ns: np.ndarray, d: np.ndarray, mat) -> np.ndarray:
    from rgraph.scene.build import AMBIENT

    color = np.asarray(AMBIENT) * mat.albedo
    origin = offset_ray(p, ng)
    for kind, vec, radiance in t.lights:
        if kind == 0:
            to_light, dist, falloff = vec / np.linalg.norm(vec), T_MAX, 1.0
        else:
            rel = vec - p
            dist = float(np.linalg.norm(rel))
            to_light, falloff = rel / max(dist, 1e-20), 1.0 / max(dist * dist, 1e-8)
        n_dot_l = float(ns @ to_light)
        if n_dot_l <= 0.0:
            continue
        blocker = intersect(t, origin, to_light)
        if blocker is not None and blocker[0] < dist:
            continue
        r = 2.0 * n_dot_l * ns - to_light
        spec = mat.ks * max(float(r @ -d), 0.0) ** mat.shininess
        color = color + radiance * falloff * (mat.albedo * n_dot_l + spec)
    return color


def trace_pixel(t: Tables, cube: np.ndarray, d0: np.ndarray, max_depth: int, stats: dict | None = None) -> np.ndarray:
    """The radiance of one camera ray: the ray tree walked depth first with an explicit stack.
    ``stats`` (optional) counts the tree's nodes per depth (``levels``) and total internal
    reflections (``tir``)."""
    color = np.zeros(3)
    stack = [(np.zeros(3), d0, np.ones(3), 0)]
    while stack:
        o, d, weight, depth = stack.pop()
        if stats is not None:
            stats["levels"][depth] = stats["levels"].get(depth, 0) + 1
        hit = intersect(t, o, d)
        if hit is None:
            color = color + weight * sample_sky(cube, d)
            continue
        dist, k, u, v = hit
        p = o + dist * d
        tri = t.triangles[k]
        ng = _normalize(np.cross(tri[1] - tri[0], tri[2] - tri[0]), -d)
        nrm = t.tri_normals[k]
        ns = _normalize((1.0 - u - v) * nrm[0] + u * nrm[1] + v * nrm[2], ng)
        if float(ng @ ns) < 0.0:
            ng = -ng
        entering = float(d @ ng) < 0.0
        ng_f, ns_f = (ng, ns) if entering else (-ng, -ns)  # facing the incoming ray
        mat = t.materials[int(t.tri_material[k])]
        opaque = 1.0 - mat.kr - mat.kt
        if opaque > 0.0:
            color = color + weight * opaque * shade_local(t, p, ng_f, ns_f, d, mat)
        if depth + 1 >= max_depth:
            continue
        reflect_w = weight * mat.kr
        if mat.kt > 0.0:
            eta = 1.0 / mat.ior if entering else mat.ior
            refr = _refract(d, ns_f, eta)
            if refr is None:
                reflect_w = reflect_w + weight * mat.kt
                if stats is not None:
                    stats["tir"] = stats.get("tir", 0) + 1
            else:
                stack.append((offset_ray(p, -ng_f), _normalize(refr, d), weight * mat.kt * mat.albedo, depth + 1))
        if float(reflect_w.max()) > 0.0:
            refl = d - 2.0 * float(d @ ns_f) * ns_f
            stack.append((offset_ray(p, ng_f), _normalize(refl, ng_f), reflect_w, depth + 1))
        assert len(stack) <= MAX_STACK
    return color


def render(t: Tables, cube: np.ndarray, size: tuple[int, int], max_depth: int, stats: dict | None = None) -> np.ndarray:
    """(h, w, 3) float64 radiance (``stats``: as ``trace_pixel``, summed over the pixels)."""
    w, h = size
    out = np.zeros((h, w, 3))
    for y in range(h):
        for x in range(w):
            out[y, x] = trace_pixel(t, cube, primary_dir(t, x, y, w, h), max_depth, stats)
    return out
