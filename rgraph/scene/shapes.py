"""Procedural shapes: indexed triangle meshes with unit vertex normals, float64 object space.

Triangles are counter-clockwise seen from outside (the right-hand normal points out). Solid
shapes are closed once coincident vertices are welded (flat-shaded edges duplicate vertices).
Every shape is deterministic: the same parameters (and seed) give the same arrays.

Axes: shapes of revolution turn around +Y and are centred on the origin.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

EPS = 1e-12


@dataclass(frozen=True)
class MeshData:
    """positions (n, 3) float64, normals (n, 3) float64 unit, indices (m, 3) uint32; optional
    uvs (n, 2) float64 and smooth_group (n,): per vertex the representative vertex of its
    smoothing group (vertices split at a UV seam share one normal: ``rgraph.scene.smoothing``)."""

    positions: np.ndarray
    normals: np.ndarray
    indices: np.ndarray
    uvs: np.ndarray | None = None
    smooth_group: np.ndarray | None = None

    @property
    def vertex_count(self) -> int:
        return len(self.positions)

    @property
    def triangle_count(self) -> int:
        return len(self.indices)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.positions.min(axis=0), self.positions.max(axis=0)


def safe_normalize(v: np.ndarray, fallback: np.ndarray | None = None) -> np.ndarray:
    """Rows of ``v`` made unit length; zero rows become ``fallback`` rows (default +Y), never NaN."""
    v = np.asarray(v, dtype=np.float64)
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    ok = length > EPS
    out = np.divide(v, np.where(ok, length, 1.0))
    if fallback is None:
        fallback = np.broadcast_to(np.array([0.0, 1.0, 0.0]), v.shape)
    return np.where(ok, out, fallback)


def vertex_normals(positions: np.ndarray, indices: np.ndarray, fallback: np.ndarray | None = None) -> np.ndarray:
    """Area-weighted vertex normals from the faces (zero-area faces add nothing; isolated or
    cancelling vertices take ``fallback``)."""
    p = positions[indices]
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])  # length = 2 * area
    corners = np.asarray(indices, dtype=np.int64).T.reshape(-1)  # all first corners, then second, third
    weights = np.concatenate([face, face, face])
    n = len(positions)
    # bincount sums in the same order as np.add.at over the three corners, several times faster
    acc = np.stack([np.bincount(corners, weights=weights[:, c], minlength=n) for c in range(3)], axis=1)
    return safe_normalize(acc, fallback)


def _mesh(positions, normals, indices) -> MeshData:
    return MeshData(np.ascontiguousarray(positions, dtype=np.float64),
                    safe_normalize(np.asarray(normals, dtype=np.float64)),
                    np.ascontiguousarray(indices, dtype=np.uint32).reshape(-1, 3))


def merge(meshes: list[MeshData]) -> MeshData:
    """One mesh of ``meshes`` (uvs kept when every part has them; smoothing groups offset)."""
    positions, normals, indices, groups, base = [], [], [], [], 0
    for m in meshes:
        positions.append(m.positions)
        normals.append(m.normals)
        indices.append(m.indices.astype(np.int64) + base)
        own = np.arange(m.vertex_count) if m.smooth_group is None else m.smooth_group.astype(np.int64)
        groups.append(own + base)
        base += m.vertex_count
    merged = _mesh(np.concatenate(positions), np.concatenate(normals), np.concatenate(indices))
    uvs = np.concatenate([m.uvs for m in meshes]) if all(m.uvs is not None for m in meshes) else None
    group = np.concatenate(groups).astype(np.uint32)
    seamless = bool(np.array_equal(group, np.arange(base)))
    return MeshData(merged.positions, merged.normals, merged.indices, uvs, None if seamless else group)


def revolve(radius: np.ndarray, height: np.ndarray, n_radial: np.ndarray, n_up: np.ndarray, segments: int,
            closed_profile: bool = False) -> MeshData:
    """Turn a profile (radius, height) around +Y. The profile runs bottom to top (for a closed
    profile, counter-clockwise in the (r, y) half plane); profile normals (n_radial, n_up).
    End points with radius 0 become single pole vertices (triangle fans, no degenerate faces)."""
    r, y = np.asarray(radius, float), np.asarray(height, float)
    nr, ny = np.asarray(n_radial, float), np.asarray(n_up, float)
    theta = 2.0 * np.pi * np.arange(segments) / segments
    s, c = np.sin(theta), np.cos(theta)
    positions, normals, index_of = [], [], {}
    for i in range(len(r)):
        if r[i] <= EPS and not closed_profile:
            index_of[i] = len(positions)
            positions.append((0.0, y[i], 0.0))
            normals.append((0.0, np.sign(ny[i]) or 1.0, 0.0))
            continue
        index_of[i] = len(positions)
        for j in range(segments):
            positions.append((r[i] * s[j], y[i], r[i] * c[j]))
            normals.append((nr[i] * s[j], ny[i], nr[i] * c[j]))
    tris = []
    rows = len(r) if closed_profile else len(r) - 1
    for i in range(rows):
        i2 = (i + 1) % len(r)
        lower_pole = r[i] <= EPS and not closed_profile
        upper_pole = r[i2] <= EPS and not closed_profile
        for j in range(segments):
            j2 = (j + 1) % segments
            a = index_of[i] + (0 if lower_pole else j)
            b = index_of[i] + (0 if lower_pole else j2)
            cc = index_of[i2] + (0 if upper_pole else j2)
            d = index_of[i2] + (0 if upper_pole else j)
            if lower_pole:
                tris.append((a, cc, d))
            elif upper_pole:
                tris.append((a, b, cc))
            else:
                tris.append((a, b, cc))
                tris.append((a, cc, d))
    return _mesh(positions, normals, tris)


def _disc(radius: float, y: float, up: bool, segments: int, inner: float = 0.0) -> MeshData:
    """A flat cap (or annulus when ``inner`` > 0) at height ``y`` facing +Y (``up``) or -Y."""
    theta = 2.0 * np.pi * np.arange(segments) / segments
    ring = np.stack([radius * np.sin(theta), np.full(segments, y), radius * np.cos(theta)], axis=1)
    n = (0.0, 1.0 if up else -1.0, 0.0)
    if inner > 0:
        iring = np.stack([inner * np.sin(theta), np.full(segments, y), inner * np.cos(theta)], axis=1)
        positions = np.concatenate([ring, iring])
        tris = []
        for j in range(segments):
            j2 = (j + 1) % segments
            o0, o1, i0, i1 = j, j2, segments + j, segments + j2
            # seen from +Y, increasing theta turns counter-clockwise (x = sin, z = cos)
            tris += [(o0, o1, i1), (o0, i1, i0)] if up else [(o0, i0, i1), (o0, i1, o1)]
        return _mesh(positions, np.tile(n, (2 * segments, 1)), tris)
    positions = np.concatenate([[(0.0, y, 0.0)], ring])
    tris = [(0, 1 + j, 1 + (j + 1) % segments) if up else (0, 1 + (j + 1) % segments, 1 + j)
            for j in range(segments)]
    return _mesh(positions, np.tile(n, (segments + 1, 1)), tris)


# ----------------------------------------------------------------------------- shapes


def box(size=(1.0, 1.0, 1.0)) -> MeshData:
    """An axis-aligned box of full extents ``size``, flat normals (24 vertices, 12 triangles)."""
    half = np.asarray(size, float).reshape(3) / 2.0
    positions, normals, tris = [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            v = np.cross(n, u)
            base = len(positions)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append((n + a * u + b * v) * half)
                normals.append(n)
            tris += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    return _mesh(positions, normals, tris)


def sphere(radius=0.5, segments=32, rings=16) -> MeshData:
    phi = np.linspace(-np.pi / 2, np.pi / 2, int(rings) + 1)
    return revolve(radius * np.cos(phi), radius * np.sin(phi), np.cos(phi), np.sin(phi), int(segments))


def capsule(radius=0.25, height=0.5, segments=32, rings=8) -> MeshData:
    """Cylinder of length ``height`` with hemispherical ends (total length height + 2 radius)."""
    phi = np.linspace(0, np.pi / 2, int(rings) + 1)
    lower = -np.pi / 2 + phi  # -90..0
    upper = phi  # 0..90
    ang = np.concatenate([lower, upper])
    off = np.concatenate([np.full(len(lower), -height / 2), np.full(len(upper), height / 2)])
    return revolve(radius * np.cos(ang), off + radius * np.sin(ang), np.cos(ang), np.sin(ang), int(segments))


def cylinder(radius=0.5, height=1.0, segments=32, stacks=1) -> MeshData:
    ys = np.linspace(-height / 2, height / 2, int(stacks) + 1)
    side = revolve(np.full(len(ys), radius), ys, np.ones(len(ys)), np.zeros(len(ys)), int(segments))
    return merge([side, _disc(radius, height / 2, True, int(segments)), _disc(radius, -height / 2, False, int(segments))])


def tube(radius=0.5, thickness=0.1, height=1.0, segments=32) -> MeshData:
    """A hollow cylinder: outer radius ``radius``, wall ``thickness``."""
    inner = radius - thickness
    if inner <= 0:
        raise ValueError("tube: thickness must be smaller than radius")
    ys = np.array([-height / 2, height / 2])
    outer = revolve(np.full(2, radius), ys, np.ones(2), np.zeros(2), int(segments))
    inner_wall = revolve(np.full(2, inner), ys[::-1], -np.ones(2), np.zeros(2), int(segments))
    return merge([outer, inner_wall, _disc(radius, height / 2, True, int(segments), inner),
                  _disc(radius, -height / 2, False, int(segments), inner)])


def torus(major=0.5, minor=0.1, segments=48, sides=16) -> MeshData:
    """A ring around +Y: tube radius ``minor`` at distance ``major`` from the axis."""
    a = 2.0 * np.pi * np.arange(int(sides)) / int(sides) - np.pi / 2  # from the bottom, counter-clockwise
    return revolve(major + minor * np.cos(a), minor * np.sin(a), np.cos(a), np.sin(a), int(segments),
                   closed_profile=True)


def plane(size=(1.0, 1.0), subdivisions=1) -> MeshData:
    """A one-sided square in XZ facing +Y (not closed)."""
    sx, sz = (size, size) if np.isscalar(size) else size
    n = int(subdivisions)
    xs, zs = np.linspace(-sx / 2, sx / 2, n + 1), np.linspace(-sz / 2, sz / 2, n + 1)
    gx, gz = np.meshgrid(xs, zs, indexing="ij")
    positions = np.stack([gx.ravel(), np.zeros(gx.size), gz.ravel()], axis=1)
    tris = []
    for i in range(n):
        for k in range(n):
            a, b, c, d = i * (n + 1) + k, (i + 1) * (n + 1) + k, (i + 1) * (n + 1) + k + 1, i * (n + 1) + k + 1
            tris += [(a, c, b), (a, d, c)]
    return _mesh(positions, np.tile((0.0, 1.0, 0.0), (len(positions), 1)), tris)


def neck(radius=0.06, height=0.2, prominence=0.012, segments=64, stacks=48) -> MeshData:
    """A neck: a slightly tapered, flattened cylinder with a thyroid prominence (Adam's apple)
    at the front (+Z), closed by flat caps. Vertex normals come from the faces."""
    segments, stacks = int(segments), int(stacks)
    ys = np.linspace(-height / 2, height / 2, stacks + 1)
    theta = 2.0 * np.pi * np.arange(segments) / segments
    t = (ys / height)[:, None]  # -0.5 .. 0.5
    r = radius * (1.0 - 0.08 * t) * (1.0 - 0.06 * np.sin(theta) ** 2)[None, :]  # taper, a little oval
    front = np.cos(theta)[None, :]
    bump = prominence * np.exp(-((t - 0.12) / 0.12) ** 2) * np.clip(front, 0, None) ** 12
    r = r + bump
    x, z = r * np.sin(theta)[None, :], r * np.cos(theta)[None, :]
    side_pos = np.stack([x, np.broadcast_to(ys[:, None], x.shape), z], axis=-1).reshape(-1, 3)
    tris = []
    for i in range(stacks):
        for j in range(segments):
            j2 = (j + 1) % segments
            a, b, c, d = i * segments + j, i * segments + j2, (i + 1) * segments + j2, (i + 1) * segments + j
            tris += [(a, b, c), (a, c, d)]
    tris_arr = np.asarray(tris)
    side_normals = vertex_normals(side_pos, tris_arr)  # on the welded side: no seam yet
    side = _split_seam(side_pos, side_normals, tris_arr, segments, stacks)
    caps = []
    for row, up in ((stacks, True), (0, False)):
        ring = side_pos[row * segments:(row + 1) * segments]
        centre = ring.mean(axis=0)
        pos = np.concatenate([centre[None], ring])
        ctris = [(0, 1 + j, 1 + (j + 1) % segments) if up else (0, 1 + (j + 1) % segments, 1 + j)
                 for j in range(segments)]
        cap = _mesh(pos, np.tile((0.0, 1.0 if up else -1.0, 0.0), (segments + 1, 1)), ctris)
        planar = 0.5 + 0.5 * (pos[:, [0, 2]] - centre[[0, 2]]) / max(float(np.abs(pos[:, [0, 2]]).max()), EPS)
        caps.append(MeshData(cap.positions, cap.normals, cap.indices, planar))
    return merge([side, *caps])


def _split_seam(pos: np.ndarray, normals: np.ndarray, tris: np.ndarray, segments: int, stacks: int) -> MeshData:
    """The side grid (rows of ``segments`` vertices) with UVs (u around, v up): the u = 1 seam
    gets its own column of vertices (copies of column 0, appended), in column 0's smoothing
    groups, and the last column's triangles use it."""
    rows = stacks + 1
    seam = pos[0::segments][:rows] if segments else pos[:0]
    seam_ids = len(pos) + np.arange(rows)
    tris = tris.copy()
    last = np.zeros(len(tris), dtype=bool)  # the two triangles of column segments - 1 in every row
    last[(np.arange(stacks)[:, None] * segments + segments - 1) * 2 + np.arange(2)] = True
    column0 = tris % segments == 0
    remap = last[:, None] & column0
    tris[remap] = seam_ids[tris[remap] // segments]
    j = np.tile(np.arange(segments), rows)
    i = np.repeat(np.arange(rows), segments)
    uv = np.concatenate([np.stack([j / segments, i / stacks], axis=1),
                         np.stack([np.ones(rows), np.arange(rows) / stacks], axis=1)])
    group = np.concatenate([np.arange(len(pos)), np.arange(rows) * segments])
    return MeshData(np.ascontiguousarray(np.concatenate([pos, seam]), dtype=np.float64),
                    np.concatenate([normals, normals[0::segments][:rows]]),
                    tris.astype(np.uint32), uv, group.astype(np.uint32))


def blob(radius=0.5, bumpiness=0.25, lobes=6, seed=0, segments=32, rings=16) -> MeshData:
    """A sphere displaced by ``lobes`` smooth seeded bumps (a polyp-like organic shape)."""
    base = sphere(1.0, segments, rings)
    rng = np.random.default_rng(int(seed))
    dirs = safe_normalize(rng.normal(size=(int(lobes), 3)))
    amps = rng.uniform(0.3, 1.0, int(lobes)) * bumpiness
    sharp = rng.uniform(2.0, 6.0, int(lobes))
    d = base.positions
    disp = 1.0 + (amps[None, :] * np.exp(sharp[None, :] * (d @ dirs.T - 1.0))).sum(axis=1)
    pos = d * (radius * disp)[:, None]
    return MeshData(pos, vertex_normals(pos, base.indices.astype(np.int64)), base.indices)


def segments(count=6, major=0.01, minor=0.002, spacing=0.008, sides=12, segments_=32) -> MeshData:
    """``count`` rings (tori around +Y) stacked along +Y, centred: e.g. tracheal cartilage rings."""
    parts = []
    for k in range(int(count)):
        ring = torus(major, minor, segments_, sides)
        off = (k - (int(count) - 1) / 2.0) * spacing
        parts.append(MeshData(ring.positions + (0.0, off, 0.0), ring.normals, ring.indices))
    return merge(parts)


def character() -> MeshData:
    """The 256-bone skinned character in its rest pose (rgraph.scene.character)."""
    from rgraph.scene.character import character as rest  # the rig imports this module

    return rest()


SHAPES: dict[str, Callable[..., MeshData]] = {
    "box": box, "sphere": sphere, "capsule": capsule, "cylinder": cylinder, "tube": tube, "torus": torus,
    "plane": plane, "neck": neck, "blob": blob, "segments": segments, "character": character,
}
CLOSED_SHAPES = tuple(s for s in SHAPES if s != "plane")


def make_shape(shape: str, params: dict | None = None, seed: int = 0) -> MeshData:
    """Build ``shape`` with scene-file ``params``; unknown parameters are a ValueError."""
    import inspect

    fn = SHAPES.get(shape)
    if fn is None:
        raise ValueError(f"unknown shape {shape!r}; known: {', '.join(sorted(SHAPES))}")
    kwargs = dict(params or {})
    if shape == "segments" and "segments" in kwargs:
        kwargs["segments_"] = kwargs.pop("segments")
    accepted = inspect.signature(fn).parameters
    if "seed" in accepted and "seed" not in kwargs:
        kwargs["seed"] = seed
    unknown = sorted(set(kwargs) - set(accepted))
    if unknown:
        raise ValueError(f"shape {shape!r}: unknown parameter(s) {', '.join(unknown)}; "
                         f"known: {', '.join(p for p in accepted if p != 'segments_')}")
    return fn(**kwargs)
