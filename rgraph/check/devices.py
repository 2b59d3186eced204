"""Multi-device plans (FORMAT.md 6): each device replayed on its own, plus cross-device ordering.

Read from the plan JSON only (no compiler or ``rgraph.plan`` code), like the rest of the
checker. Rules:

- every pass accesses only resources of its own ``device`` (resources and heaps carry one);
- a pass that receives data from another device (``params.copy_from = {device, pass}``) waits
  on that device (``waits[].device``) for a timeline value the sending pass signals on its
  own queue, and the sending pass exists on that device and runs earlier in the plan;
- a cross-device wait without such a copy, or naming a value nobody signals, is reported;
- each device's passes, resources and heaps, with cross-device waits and the signals they
  consume left out, form a one-device plan that the usual replay must find clean.
"""

from __future__ import annotations

import copy
from typing import Any

from rgraph.check import hazards as hz


def _hazard(kind: str, p: dict[str, Any] | None, resource: str | None, message: str) -> hz.Hazard:
    return hz.Hazard(kind, None if p is None else p["index"], None if p is None else p["name"], resource, None,
                     message)


def cross_device_hazards(plan: dict[str, Any]) -> list[hz.Hazard]:
    """Findings of the cross-device rules (module docstring)."""
    out: list[hz.Hazard] = []
    owner = {r["name"]: r.get("device", 0) for r in plan["resources"]}
    by_name = {p["name"]: p for p in plan["passes"]}
    for p in plan["passes"]:
        for a in p["accesses"]:
            if owner.get(a["resource"], 0) != p["device"]:
                out.append(_hazard(hz.RAW, p, a["resource"], f"pass {p['index']} '{p['name']}' on device {p['device']} "
                                   f"accesses '{a['resource']}' of device {owner.get(a['resource'], '(none)')}"))
        source = (p.get("params") or {}).get("copy_from")
        cross = [w for w in p["waits"] if w.get("device") is not None]
        if source is None:
            for w in cross:
                out.append(_hazard(hz.SEMAPHORE, p, None, f"pass {p['index']} '{p['name']}' waits on device "
                                   f"{w['device']} but copies nothing from it"))
            continue
        sender = by_name.get(source.get("pass"))
        if sender is None or sender["device"] != source.get("device") or sender["index"] > p["index"]:
            out.append(_hazard(hz.RAW, p, None, f"pass {p['index']} '{p['name']}' copies from "
                               f"{source.get('pass')!r} on device {source.get('device')}, which does not run "
                               f"there before it"))
            continue
        signalled = max((s["value"] for s in sender["signals"] if s["queue"] == sender["queue"]), default=None)
        ok = signalled is not None and any(w["device"] == sender["device"] and w["queue"] == sender["queue"]
                                           and w["value"] >= signalled for w in cross)
        if not ok:
            out.append(_hazard(hz.RAW, p, None, f"RAW across devices: pass {p['index']} '{p['name']}' on device "
                               f"{p['device']} reads what '{sender['name']}' wrote on device {sender['device']} "
                               f"without waiting for its signal (device {sender['device']} {sender['queue']} "
                               f">= {signalled})"))
    return out


def device_plan(plan: dict[str, Any], device: int) -> dict[str, Any]:
    """Device ``device``'s passes, resources and heaps as a one-device plan (indices renumbered)."""
    consumed = {(w["device"], w["queue"], w["value"]) for p in plan["passes"] for w in p["waits"]
                if w.get("device") is not None}
    out = copy.deepcopy({k: v for k, v in plan.items() if k not in ("passes", "resources", "heaps", "multi_device")})
    passes = [copy.deepcopy(p) for p in plan["passes"] if p["device"] == device]
    index = {p["index"]: i for i, p in enumerate(passes)}
    for p in passes:
        p["index"], p["device"] = index[p["index"]], 0
        p["waits"] = [w for w in p["waits"] if w.get("device") is None]
        p["signals"] = [s for s in p["signals"] if (device, s["queue"], s["value"]) not in consumed]
    resources = []
    for r in plan["resources"]:
        if r.get("device", 0) != device:
            continue
        r = copy.deepcopy(r)
        r.pop("device", None)
        for key in ("first", "last"):
            if r.get(key) is not None:
                r[key] = index[r[key]]
        resources.append(r)
    out["passes"], out["resources"] = passes, resources
    out["heaps"] = [{k: v for k, v in h.items() if k != "device"} for h in plan["heaps"]
                    if h.get("device", 0) == device]
    out["outputs"] = [o for o in plan.get("outputs", []) if any(r["name"] == o for r in resources)]
    return out
