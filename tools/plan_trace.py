"""Write a plan's transient resources as a MiniMalloc CSV trace (``rgraph place`` reads it).

    python tools/plan_trace.py PLAN.json -o data/traces/NAME.csv

Rows: ``id`` (the resource name), ``lower`` = first pass, ``upper`` = last pass + 1
(exclusive), ``size`` = bytes, ``alignment``. Only transient resources alias, so only they
are written; the resources of every memory class share one trace.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def trace_rows(plan: dict) -> list[tuple[str, int, int, int, int]]:
    rows = []
    for r in plan["resources"]:
        if r.get("lifetime", "transient") == "transient" and r.get("first") is not None:
            rows.append((r["name"], r["first"], r["last"] + 1, r["bytes"], r.get("alignment") or 1))
    return sorted(rows, key=lambda row: (row[1], row[0]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("plan", type=Path)
    parser.add_argument("-o", "--output", type=Path, required=True)
    args = parser.parse_args()
    rows = trace_rows(json.loads(args.plan.read_text()))
    lines = ["id,lower,upper,size,alignment"] + [",".join(map(str, row)) for row in rows]
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
