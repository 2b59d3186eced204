"""Shared helpers of the report tests: fixture plans and running ``rgraph inspect``."""

from __future__ import annotations

import json
from pathlib import Path

from rgraph.cli import main

PLANS = Path(__file__).parent
FORWARD = PLANS / "forward.json"
MINIMAL = PLANS / "minimal.json"


def load(path: Path) -> dict:
    return json.loads(path.read_text())


def inspect(capsys, *args: str) -> tuple[int, str, str]:
    """Run ``rgraph inspect ARGS``; (exit code, stdout, stderr)."""
    code = main(["inspect", *args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err
