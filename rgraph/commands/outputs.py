"""Arguments checked before any work starts: output files, counts, pass params.

A file the command will write is checked when the command starts, not after the frame ran:
its folder must exist and be writable, and the path must not be a folder, a device that
refuses writes (``/dev/full``) or otherwise unwritable. Each problem is one located line.
"""

from __future__ import annotations

import argparse
import errno
import os
import stat
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rgraph.errors import Location, RGraphError, quote

COMMAND_LINE = "<command line>"
MAX_FRAMES = 1_000_000


def warmup_seconds(text: str) -> float:
    """argparse type for ``--warmup``: seconds in 0..600 (NaN and inf refused)."""
    try:
        value = float(text) if len(text) <= 12 else None
    except ValueError:
        value = None
    if value is None or not 0.0 <= value <= 600.0:
        raise argparse.ArgumentTypeError(f"expected seconds in 0..600, got {quote(text)}")
    return value


def frame_count(text: str) -> int:
    """argparse type for ``--frames``: an integer in 1..MAX_FRAMES (``1e20`` is refused)."""
    try:
        value = int(text) if len(text) <= 12 else None
    except ValueError:
        value = None
    if value is None or not 1 <= value <= MAX_FRAMES:
        raise argparse.ArgumentTypeError(f"expected an integer in 1..{MAX_FRAMES:,}, got {quote(text)}")
    return value


def output_path(text: str) -> Path:
    """argparse type for an output file: a name ending in '/' names a folder, not a file."""
    if not text or text.endswith(("/", os.sep)):
        raise argparse.ArgumentTypeError(f"expected a file name, got {quote(text)}")
    return Path(text)


def check_output_file(path: str | Path, flag: str) -> None:
    """Refuse an output path that cannot be written, without creating or truncating it."""
    text = str(path)
    where = f"{COMMAND_LINE}"
    if not text or "\x00" in text or text.endswith("/"):
        raise RGraphError.in_file(where, f"{flag}: {quote(text)} is not a file name")
    p = Path(text)
    try:
        info = os.stat(p)
    except FileNotFoundError:
        info = None
    except OSError as exc:
        raise RGraphError.in_file(where, f"{flag}: cannot write {quote(text)}: {exc.strerror or exc}") from None
    if info is not None:
        if stat.S_ISDIR(info.st_mode):
            raise RGraphError.in_file(where, f"{flag}: {quote(text)} is a directory, expected a file name")
        if not stat.S_ISREG(info.st_mode):
            _probe_device(p, flag, text)
            return
        try:  # opening to append neither creates nor truncates
            os.close(os.open(p, os.O_WRONLY | os.O_APPEND))
        except OSError as exc:
            raise RGraphError.in_file(where, f"{flag}: cannot write {quote(text)}: {exc.strerror or exc}") from None
        return
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise RGraphError.in_file(where, f"{flag}: cannot write {quote(text)}: folder {quote(str(folder))} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise RGraphError.in_file(where, f"{flag}: cannot write {quote(text)}: folder {quote(str(folder))} is not writable")
    if len(os.fsencode(p.name)) > 255:
        raise RGraphError.in_file(where, f"{flag}: file name is longer than 255 bytes")


def _probe_device(p: Path, flag: str, text: str) -> None:
    """A character device or FIFO: writable only if a test write succeeds (``/dev/full`` fails)."""
    try:
        fd = os.open(p, os.O_WRONLY | os.O_NONBLOCK)
    except OSError as exc:
        raise RGraphError.in_file(COMMAND_LINE, f"{flag}: cannot write {quote(text)}: {exc.strerror or exc}") from None
    try:
        os.write(fd, b"")
        if os.path.realpath(p) == "/dev/full":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    except OSError as exc:
        raise RGraphError.in_file(COMMAND_LINE, f"{flag}: cannot write {quote(text)}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def write_output(path: str | Path, text: str, flag: str) -> None:
    """Write ``text`` to ``path``; an OS refusal (a full disk, ...) is a located error, not a traceback."""
    try:
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(text)
    except OSError as exc:
        raise RGraphError.in_file(COMMAND_LINE, f"{flag}: cannot write {quote(str(path))}: {exc.strerror or exc}") from None


def _param_location(plan: Mapping[str, Any], name: str) -> Location:
    """Where the graph that made ``plan`` sets param ``name`` (its first line if unknown)."""
    from rgraph.spec.loader import load_graph

    source = str(plan.get("source") or plan.get("graph") or "<plan>")
    try:
        located = load_graph(source).params.get(name)
    except (RGraphError, OSError):
        located = None
    return located.loc() if located is not None else Location(source)


def params_view(spec: Any, graph: str) -> dict:
    """The passes' impls and params of a specialized graph as a plan would carry them (what
    ``check_pass_params`` reads), without touching a device."""
    return {"source": str(spec.source) if getattr(spec, "source", None) else graph, "params": dict(spec.params),
            "scene_source": spec.scene_source,
            "passes": [{"name": p.name, "impl": p.impl, "params": dict(p.params)} for p in spec.passes]}


def check_pass_params(plan: Mapping[str, Any], user_params: Mapping[str, Any]) -> None:
    """Every pass's params against its implementation's declared schema (before the device opens);
    an output param must come from the command line and be writable."""
    from rgraph.impl import lookup, param_problems

    problems = param_problems(plan, user_params)
    if problems:
        name, message = problems[0]
        if name in user_params:
            raise RGraphError.in_file(COMMAND_LINE, message)
        raise RGraphError.at(_param_location(plan, name), message)
    for p in plan.get("passes", []):
        try:
            schema = lookup(p["impl"]).param_schema if p.get("impl") else {}
        except KeyError:
            continue
        for name, spec in schema.items():
            value = {**(plan.get("params") or {}), **(p.get("params") or {})}.get(name)
            if spec.output and value:
                check_output_file(str(value), f"-p {name}")
