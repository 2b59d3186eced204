"""Scene generators (FORMAT.md section 7): a ``lights:`` item ``{generate: point, ...}`` -> lights.

``expand_lights`` replaces each generator by ``count`` point lights drawn from
``numpy.random.default_rng(seed)`` in a fixed order (positions uniform in ``bounds``, then radii
uniform in ``radius``, intensities uniform in ``intensity``, colours uniform in [0.25, 1]^3
scaled to a maximum channel of 1 unless ``color`` is given), so a scene file always stands for
the same lights.
"""

from __future__ import annotations

import numpy as np

from rgraph.spec.scene import Light, LightGenerator


def generated_lights(gen: LightGenerator) -> dict[str, np.ndarray]:
    """The generator's lights as arrays: position (n, 3), radius (n,), intensity (n,), color (n, 3)."""
    rng = np.random.default_rng(gen.seed)
    lo, hi = (np.asarray(b, dtype=np.float64) for b in gen.bounds)
    n = gen.count
    position = lo + (hi - lo) * rng.random((n, 3))
    radius = gen.radius[0] + (gen.radius[1] - gen.radius[0]) * rng.random(n)
    intensity = gen.intensity[0] + (gen.intensity[1] - gen.intensity[0]) * rng.random(n)
    if gen.color is None:
        color = 0.25 + 0.75 * rng.random((n, 3))
        color /= color.max(axis=1, keepdims=True)
    else:
        color = np.broadcast_to(np.asarray(gen.color, dtype=np.float64), (n, 3))
    return {"position": position, "radius": radius, "intensity": intensity, "color": color}


def expand_lights(items: list[Light | LightGenerator]) -> list[Light]:
    """Authored lights as they are, each generator replaced by its point lights (in list order)."""
    out: list[Light] = []
    for item in items:
        if isinstance(item, Light):
            out.append(item)
            continue
        g = generated_lights(item)
        out.extend(Light.model_construct(type="point", direction=None, position=list(map(float, p)),
                                         color=list(map(float, c)), intensity=float(i), radius=float(r),
                                         shadows=False, cone=[30.0, 45.0])
                   for p, c, i, r in zip(g["position"], g["color"], g["intensity"], g["radius"], strict=True))
    return out
