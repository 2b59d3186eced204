"""Acceleration-structure sizes in a device profile (pure; shared by capture and prediction).

A profile's ``accel`` section holds, per level ("bottom": triangle BLAS, "top": instance TLAS),
measured ``[count, max_vertex, update, size, build_scratch, update_scratch]`` samples and, when
one fits, a rule per quantity: ``a * count + b`` for counts from ``from`` on (smaller counts
are measured samples only). A rule is kept only if it reproduces every sample it covers and
the sizes do not depend on the vertex count or the update flag beyond what was measured.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rgraph.errors import RGraphError

#: Primitive/instance counts measured at capture time.
CAPTURE_COUNTS = (*range(1, 17), 24, 32, 48, 64, 100, 128, 256, 500, 512, 1000, 1024, 4096, 10000, 12345, 65536,
                  100000, 262144, 1000000)
QUANTITIES = ("size", "build", "update")


def fit_affine(points: Sequence[tuple[int, int]]) -> dict[str, int] | None:
    """``{"a", "b", "from"}``: value = a * n + b for every point with n >= from (the smallest
    such ``from``), from the two largest counts; None when not even those fit with integers."""
    pts = sorted(set(points))
    if len(pts) < 3:
        return None
    (n1, v1), (n2, v2) = pts[-2], pts[-1]
    if (v2 - v1) % (n2 - n1):
        return None
    a = (v2 - v1) // (n2 - n1)
    b = v2 - a * n2
    start = n2
    for n, value in reversed(pts):
        if a * n + b != value:
            break
        start = n
    return {"a": a, "b": b, "from": start} if start <= pts[-3][0] else None


def fit_level(samples: Sequence[Sequence[int]]) -> dict[str, Any] | None:
    """Rules for one level's samples, or None when sizes depend on more than the count."""
    by_count: dict[tuple[int, bool], set[tuple[int, int, int]]] = {}
    for count, _max_vertex, update, size, build, upd in samples:
        by_count.setdefault((count, bool(update)), set()).add((size, build, upd))
    if any(len(v) > 1 for v in by_count.values()):
        return None  # depends on the vertex count
    rules: dict[str, Any] = {}
    for update in (False, True):
        points = {c: next(iter(v)) for (c, u), v in by_count.items() if u == update}
        if not points:
            continue
        per = {}
        for qi, q in enumerate(QUANTITIES):
            rule = fit_affine([(c, vals[qi]) for c, vals in points.items()])
            if rule is None:
                return None
            per[q] = rule
        rules["update" if update else "build"] = per
    return rules


def predict(section: dict[str, Any], level: str, count: int, max_vertex: int, update: bool,
            profile_name: str) -> tuple[int, int, int]:
    """(size, build scratch, update scratch) of one structure from a profile's ``accel`` section."""
    entry = section.get(level)
    if entry is None:
        raise RGraphError.in_file("<profile>", f"device profile {profile_name!r} has no {level}-level sizes")
    for c, mv, u, size, build, upd in entry["samples"]:
        if c == count and bool(u) == update and (mv == max_vertex or entry.get("rules") is not None):
            return size, build, upd
    rules = (entry.get("rules") or {}).get("update" if update else "build")
    if rules is None or count < min(r["from"] for r in rules.values()):
        raise RGraphError.in_file(
            "<profile>", f"device profile {profile_name!r}: no verified {level}-level size rule for {count} "
            f"{'triangles' if level == 'bottom' else 'instances'} (compile on the device instead)")
    return tuple(r["a"] * count + r["b"] for r in (rules[q] for q in QUANTITIES))  # type: ignore[return-value]
