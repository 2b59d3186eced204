"""Which passes a knob changes, and their GPU time: the x axis of its Pareto plot.

A pass is changed by knob ``K`` when, among the renderings that move ``K`` (and the
defaults), (a) its implementation looked ``K`` up (``RunResult.params_read``, recorded by
``PassSetup.params``), (b) it accesses a resource whose description in the compiled plan
(kind, format, extent, layers, mips, samples, buffer size) differs between them, e.g. a
shadow map sized ``${params.shadow.size}``, (c) its own plan params differ, or (d) it runs in
some of them only. Memory placement (heaps, offsets) is not a description: it moves with any
size.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

DESCRIPTION = ("kind", "format", "extent", "layers", "mips", "samples", "size_bytes")


def changed_passes(knob: str, plans: Sequence[dict], params_read: Sequence[dict[str, list[str]]]) -> list[str]:
    """Names of the passes ``knob`` changes, in the first plan's order (then the others')."""
    changed = {name for read in params_read for name, names in read.items() if knob in names}
    described = [{r["name"]: json.dumps([r.get(f) for f in DESCRIPTION]) for r in plan["resources"]}
                 for plan in plans]
    resources = {name for d in described for name in d}
    differing = {n for n in resources if len({d.get(n) for d in described}) > 1}
    passes = [{p["name"]: p for p in plan["passes"]} for plan in plans]
    order = list(dict.fromkeys(name for by_name in passes for name in by_name))
    for name in order:
        entries = [by_name.get(name) for by_name in passes]
        if any(e is None for e in entries) or len({json.dumps(e.get("params", {}), sort_keys=True)
                                                  for e in entries if e is not None}) > 1:
            changed.add(name)
        elif any(a["resource"] in differing for e in entries if e is not None for a in e["accesses"]):
            changed.add(name)
    return [name for name in order if name in changed]


def passes_ms(pass_ms: dict[str, float | None], passes: Sequence[str]) -> float | None:
    """GPU ms of ``passes`` in one rendering (a pass it did not run counts 0; an untimed one
    makes the sum unknown)."""
    values = [pass_ms[p] if p in pass_ms else 0.0 for p in passes]
    return None if not pass_ms or any(v is None for v in values) else float(sum(values))  # type: ignore[arg-type]
