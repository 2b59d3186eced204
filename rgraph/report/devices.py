"""``rgraph inspect`` of a multi-device plan: the split, each device's schedule and the copies."""

from __future__ import annotations

from typing import Any

from rich.table import Table


def print_devices(console: Any, plan: dict[str, Any]) -> None:
    """Per-device schedule (one column per device, one row per plan pass) and the cross-device copies."""
    info = plan.get("multi_device")
    if not info:
        return
    n = int(info["devices"])
    console.print(f"{info['split']} over {n} devices, balance {info['balance']}; "
                  f"composite before: {info.get('cut') or '(end of frame)'} -- {info.get('reason', '')}")
    if info.get("bands"):
        console.print("bands (y, rows): " + ", ".join(f"device {d}: {tuple(b)}" for d, b in enumerate(info["bands"])))
    table = Table(title="schedule per device")
    table.add_column("#", justify="right")
    for d in range(n):
        table.add_column(f"device {d}")
    for p in plan["passes"]:
        note = ""
        params = p.get("params") or {}
        if "rgraph.scissor" in params:
            note = f" (scissor {params['rgraph.scissor']})"
        elif "rgraph.draws" in params:
            note = f" (draws {params['rgraph.draws'][0]}/{params['rgraph.draws'][1]})"
        cells = [""] * n
        cells[p["device"]] = f"{p['name']}{note}"
        table.add_row(str(p["index"]), *cells)
    console.print(table)
    copies = Table(title="cross-device copies (through host memory)")
    for col in ("from", "pass", "to", "pass", "wait", "bytes"):
        copies.add_column(col)
    sizes = {r["name"]: r.get("size_bytes") or r["bytes"] for r in plan["resources"]}
    for p in plan["passes"]:
        src = (p.get("params") or {}).get("copy_from")
        if not src:
            continue
        waits = [w for w in p["waits"] if w.get("device") is not None]
        landing = next((a["resource"] for a in p["accesses"] if not a["write"]), "?")
        copies.add_row(f"device {src['device']}", src["pass"], f"device {p['device']}", p["name"],
                       ", ".join(f"d{w['device']}.{w['queue']} >= {w['value']}" for w in waits) or "MISSING",
                       str(sizes.get(landing, "?")))
    console.print(copies)
