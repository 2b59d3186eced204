"""Reading files named by the user or by a file: regular files only, never more than a cap.

``/dev/zero`` never ends and a FIFO blocks forever, so anything that is not a regular file
is refused before it is opened; the size is checked before and while reading.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

from rgraph.errors import RGraphError

MAX_BYTES = 4 * 1024 * 1024  # graphs and scenes: a 16,000-pass graph is 2.2 MB


def read_text(path: Path, display: str, what: str = "a YAML file", limit: int = MAX_BYTES) -> str:
    """Read ``path`` as UTF-8, reporting the line and column of the first bad byte.

    Only regular files are read (not devices, FIFOs or sockets: ``/dev/zero`` never ends and a
    FIFO blocks), and never more than ``limit`` bytes."""
    data = read_bytes(path, display, what, limit)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[: exc.start]
        line = before.count(b"\n") + 1
        col = len(before) - (before.rfind(b"\n") + 1) + 1
        raise RGraphError.in_file(
            display, f"file is not valid UTF-8 (byte 0x{data[exc.start]:02x})", line, col
        ) from None


def read_bytes(path: Path, display: str, what: str, limit: int) -> bytes:
    """The bytes of the regular file ``path`` (at most ``limit``), or a located error."""
    try:
        info = os.stat(path)
        if stat.S_ISDIR(info.st_mode):
            raise RGraphError.in_file(display, f"is a directory, expected {what}")
        if not stat.S_ISREG(info.st_mode):
            raise RGraphError.in_file(display, f"is not a regular file (a device, FIFO or socket), expected {what}")
        if info.st_size > limit:
            raise RGraphError.in_file(display, f"file is larger than {_size(limit)}")
        with open(path, "rb") as handle:
            data = handle.read(limit + 1)
    except FileNotFoundError:
        raise RGraphError.in_file(display, "no such file") from None
    except ValueError:  # a NUL byte in the name
        raise RGraphError.in_file(display, "file name contains a NUL byte") from None
    except OSError as exc:
        raise RGraphError.in_file(display, f"cannot read: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise RGraphError.in_file(display, f"file is larger than {_size(limit)}")
    return data


def _size(limit: int) -> str:
    return f"{limit // (1024 * 1024)} MiB" if limit >= 1024 * 1024 else f"{limit:,} bytes"


def line_col(text: str, offset: int) -> tuple[int, int]:
    """1-based line and column of character ``offset`` of ``text``."""
    return text.count("\n", 0, offset) + 1, offset - (text.rfind("\n", 0, offset) + 1) + 1


def check_bracket_depth(text: str, file: str, limit: int, tokens: re.Pattern[str], what: str) -> None:
    """Refuse ``[``/``{`` nested deeper than ``limit`` (``tokens`` matches brackets and the quoted
    strings to skip), at the bracket that goes too deep -- before a recursive parser sees them."""
    if text.count("[") + text.count("{") <= limit:
        return
    depth = 0
    for match in tokens.finditer(text):
        token = match.group()
        if token in "[{":
            depth += 1
            if depth > limit:
                raise RGraphError.in_file(file, f"{what} nested deeper than {limit} levels", *line_col(text, match.start()))
        elif token in "]}":
            depth = max(0, depth - 1)
