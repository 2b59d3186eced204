"""``--json`` output of the commands (schema: docs/cli-json.md).

Every document is one JSON object on stdout with ``format`` (``rgraph-<command>/1``), ``ok``
and ``diagnostics`` (a list of ``{severity, file, line, col, message}``); the rest depends
on the command. Bad input still exits 2, with the diagnostics in the document instead of
``FILE:LINE:COL: error:`` lines on stderr.
"""

from __future__ import annotations

import json
import sys
from typing import Any, TextIO

from rgraph.errors import Diagnostic, Location


def diagnostic(severity: str, location: Location, message: str) -> dict[str, Any]:
    return {"severity": severity, "file": location.file, "line": location.line, "col": location.col,
            "message": message}


def error_objects(diagnostics: list[Diagnostic]) -> list[dict[str, Any]]:
    return [diagnostic("error", d.location, d.message) for d in diagnostics]


def document(command: str, ok: bool, diagnostics: list[dict[str, Any]] | None = None, **body: Any) -> dict[str, Any]:
    return {"format": f"rgraph-{command}/1", "ok": ok, "diagnostics": diagnostics or [], **body}


def emit(doc: dict[str, Any], out: TextIO | None = None) -> None:
    (out or sys.stdout).write(json.dumps(doc, indent=1, sort_keys=True) + "\n")
