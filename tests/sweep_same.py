"""What "the same sweep" means for a parallel sweep and the one-process one: every output
file but the Pareto plots byte-identical after measured times are masked (CSV columns
``ms.*``/``*_ms``, Markdown table columns headed with ``ms``, the per-pass time table), and
the same files written (the Pareto plots place points by time, so only their presence is
compared)."""

from __future__ import annotations

import csv
import re
from pathlib import Path

_MS = re.compile(r"\bms\b")


def is_time_column(name: str) -> bool:
    return name.startswith("ms.") or name.endswith("_ms")


def timeless_csv(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return [{k: v for k, v in row.items() if not is_time_column(k)} for row in csv.DictReader(f)]


def timeless_md(text: str) -> str:
    out: list[str] = []
    masked: set[int] = set()
    section = ""
    for line in text.splitlines():
        if line.startswith("## "):
            section, masked = line, set()
        if not line.startswith("|"):
            out.append(line)
            masked = set()
            continue
        cells = line.strip("|").split("|")
        if not masked and not set(line) <= set("|-: "):
            if "ms per pass" in section:
                masked = set(range(1, len(cells)))
            else:
                masked = {i for i, c in enumerate(cells) if _MS.search(c)} or {-1}
            out.append(line)  # the header
            continue
        out.append("|".join("~" if i in masked and not set(c) <= set("-: ") else c for i, c in enumerate(cells)))
    return "\n".join(out)


def files(out: Path) -> dict[str, bytes | None]:
    """Relative path -> bytes (None for the time-dependent Pareto plots)."""
    return {p.relative_to(out).as_posix(): None if p.name.startswith("pareto_") else p.read_bytes()
            for p in sorted(out.rglob("*")) if p.is_file() and p.suffix == ".png"}


def assert_same_sweep(one: Path, other: Path) -> None:
    assert timeless_csv(one / "sweep.csv") == timeless_csv(other / "sweep.csv")
    assert timeless_md((one / "sweep.md").read_text()) == timeless_md((other / "sweep.md").read_text())
    a, b = files(one), files(other)
    assert sorted(a) == sorted(b)
    different = [name for name in a if a[name] != b[name]]
    assert not different, f"differ: {different}"
