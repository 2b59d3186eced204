"""Whether two sweep output folders are the same sweep: every output but the measured times.

CSV columns ``ms.*``/``*_ms``, Markdown table columns headed with ``ms`` and the per-pass
time table are masked; images and error maps must be byte-identical; the Pareto plots place
points by time, so only their presence is compared. A sweep in worker processes
(``--workers``, ``--ray``) gives the same sweep as the one-process one (tests/sweep); on a GPU
``benchmarks/sweep_throughput.py`` checks it too."""

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


def differences(one: Path, other: Path) -> list[str]:
    """What differs between two sweeps' outputs besides measured times (empty: the same)."""
    out = []
    if timeless_csv(one / "sweep.csv") != timeless_csv(other / "sweep.csv"):
        out.append("sweep.csv")
    if timeless_md((one / "sweep.md").read_text()) != timeless_md((other / "sweep.md").read_text()):
        out.append("sweep.md")
    a, b = files(one), files(other)
    out += [f"{name} (only in one)" for name in sorted(set(a) ^ set(b))]
    out += [name for name in sorted(set(a) & set(b)) if a[name] != b[name]]
    return out


def relative_time_changes(one: Path, other: Path) -> list[float]:
    """|t_other - t_one| / t_one of every setting's frame GPU time present in both."""
    def times(path: Path) -> dict[str, float]:
        with (path / "sweep.csv").open() as f:
            return {r["setting"]: float(r["total_ms"]) for r in csv.DictReader(f) if r["total_ms"]}

    a, b = times(one), times(other)
    return [abs(b[k] - a[k]) / a[k] for k in a if k in b and a[k] > 0]
