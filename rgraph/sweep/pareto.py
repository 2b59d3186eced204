"""Pareto fronts of (time, error) points."""

from __future__ import annotations

import math
from collections.abc import Sequence


def pareto_front(ms: Sequence[float | None], error: Sequence[float | None], *,
                 lower_is_better: bool = True) -> list[int]:
    """Indices of the points no other point dominates, by increasing time.

    A point dominates another when it is no slower and no worse, and strictly better in
    one of the two. Points with a missing or NaN coordinate take no part."""
    sign = 1.0 if lower_is_better else -1.0
    points = [(i, float(t), sign * float(e)) for i, (t, e) in enumerate(zip(ms, error, strict=True))
              if t is not None and e is not None and not math.isnan(t) and not math.isnan(e)]
    front = []
    for i, t, e in points:
        dominated = any(t2 <= t and e2 <= e and (t2 < t or e2 < e) for j, t2, e2 in points if j != i)
        if not dominated:
            front.append((t, e, i))
    return [i for _t, _e, i in sorted(front)]
