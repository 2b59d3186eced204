"""Whether a plan's frames depend on earlier frames through memory (history, accumulation)."""

from __future__ import annotations

from typing import Any

_KEPT = ("persistent", "imported")


def carries_state(plan: dict[str, Any]) -> bool:
    """True when some persistent or imported resource is read in a frame before the frame
    writes it, and written too: what a frame computes then depends on what earlier frames
    left there. Resources written in full before any read (per-frame LUTs) or only read
    (uploaded inputs) carry nothing; an access that reads and writes (a loaded attachment, a
    refit) counts as a read first."""
    kept = {r["name"] for r in plan["resources"] if r["lifetime"] in _KEPT}
    read_first: set[str] = set()
    written: set[str] = set()
    for p in plan["passes"]:
        for a in p["accesses"]:
            name = a["resource"]
            if name not in kept:
                continue
            if name not in written and name not in read_first and any(x.endswith("_READ") for x in a["access"]):
                read_first.add(name)
            if a.get("write"):
                written.add(name)
    return bool(read_first & written)
