"""Transfer stages widened to ALL_TRANSFER for Khronos validation 1.3.239.

The compiler names the stage a transfer usage runs in (``COPY`` for ``transfer_src`` and
``transfer_dst`` in the usage table of the compiler package). Synchronization validation 1.3.239 misreports
barriers and semaphore waits that name the narrower transfer stages (COPY, BLIT, RESOLVE,
CLEAR) for copy commands, so the runtime records them as ALL_TRANSFER, a superset (the same
dependency or a wider one). This rewrite applies to the whole plan before lowering: pass
accesses, barriers and releases, semaphore waits and signals, and the resources' final
states (which initialisation and readback barriers start from), so that every later
rewrite sees the stages that will be recorded. Until this rewrite existed the compiler's
usage table itself said ALL_TRANSFER.
"""

from __future__ import annotations

import copy

NARROW_TRANSFER = frozenset({"COPY", "BLIT", "RESOLVE", "CLEAR"})
WIDE = "ALL_TRANSFER"


def _widen(stages: list[str]) -> list[str]:
    if not any(s in NARROW_TRANSFER for s in stages):
        return stages
    out = [s for s in stages if s not in NARROW_TRANSFER]
    return out if WIDE in out else sorted([*out, WIDE])


def widen_transfer_stages(plan: dict) -> dict:
    """A copy of ``plan`` whose narrow transfer stages are ALL_TRANSFER (``plan`` is not changed)."""
    out = copy.deepcopy(plan)
    for p in out.get("passes", []):
        for a in p.get("accesses", []):
            a["stages"] = _widen(a["stages"])
        for key in ("barriers", "releases"):
            for b in p.get(key, []):
                for side in ("src", "dst"):
                    b[side]["stages"] = _widen(b[side]["stages"])
        for key in ("waits", "signals"):
            for w in p.get(key, []):
                w["stages"] = _widen(w["stages"])
    for r in out.get("resources", []):
        for key in ("initial", "final"):
            state = r.get(key)
            if isinstance(state, dict) and "stages" in state:
                state["stages"] = _widen(state["stages"])
    return out
