"""The ``--barriers`` view: every synchronization command of the plan, in execution order.

Per pass: its semaphore waits, its barriers, (the pass), its queue-family releases, its
semaphore signals -- the order docs/plan.md prescribes.
"""

from __future__ import annotations

from typing import Any

from rgraph.report.fmt import flags, subresource, sync_state

Plan = dict[str, Any]


def barrier_text(b: dict[str, Any], transfer_word: str) -> str:
    """``res[mips a:b layers c:d] SRC -> DST`` plus the queue transfer and the aliased occupant."""
    src, dst = b["src"], b["dst"]
    text = f"{b['resource']}{subresource(b.get('subresource'))} {sync_state(src)} -> {sync_state(dst)}"
    src_q, dst_q = src.get("queue"), dst.get("queue")
    if src_q and dst_q and src_q != dst_q:
        text += f" {transfer_word} {src_q}->{dst_q}"
    aliases = b.get("aliases")
    if aliases:  # docs/plan.md: a name; the compiler may list several previous occupants
        text += f" (aliases {aliases if isinstance(aliases, str) else ', '.join(aliases)})"
    return text


def barrier_lines(plan: Plan) -> list[str]:
    """One line per wait, barrier, release and signal, in execution order."""
    lines: list[str] = []
    for p in plan["passes"]:
        name = p["name"]
        for w in p.get("waits") or []:
            lines.append(f"wait before {name}: {w['queue']} timeline >= {w['value']} (dst {flags(w.get('stages'))})")
        for b in p.get("barriers") or []:
            lines.append(f"before {name}: {barrier_text(b, 'acquire')}")
        for b in p.get("releases") or []:
            lines.append(f"after {name}: {barrier_text(b, 'release')}")
        for s in p.get("signals") or []:
            lines.append(f"signal after {name}: {s['queue']} timeline = {s['value']} (src {flags(s.get('stages'))})")
    return lines


def barrier_totals(plan: Plan) -> str:
    """A closing count line."""
    passes = plan["passes"]

    def count(key: str) -> int:
        return sum(len(p.get(key) or []) for p in passes)

    return (
        f"{count('barriers')} barriers, {count('releases')} releases, "
        f"{count('waits')} waits, {count('signals')} signals"
    )
