"""``--devices``, ``--split`` and ``--balance`` (FORMAT.md section 6) for compile, inspect and run."""

from __future__ import annotations

import argparse
from typing import Any

from rgraph.errors import RGraphError

COMMAND_LINE = "<command line>"


def add_split_arguments(parser: argparse.ArgumentParser, *, indices: bool = False) -> None:
    what = ("device indices as listed by 'rgraph devices', e.g. 0,1 (0,0: two logical devices on one)"
            if indices else "number of devices the plan is split over (default 1)")
    parser.add_argument("--devices", default=None, help=what)
    parser.add_argument("--split", choices=("sort-first", "sort-last"), default=None,
                        help="sort-first: horizontal bands per device; sort-last: the scene's draws split, "
                             "depth composited")
    parser.add_argument("--balance", choices=("static", "dynamic"), default="static",
                        help="static: equal shares; dynamic: shares from measured per-device times (run)")
    if indices:
        parser.add_argument("--transfer", choices=("auto", "shared", "staged"), default="auto",
                            help="tiles between devices: shared (one host allocation imported by both, "
                                 "VK_EXT_external_memory_host), staged (readback + upload); auto: shared where offered")
        parser.add_argument("--pipelined", action="store_true",
                            help="start the senders' next frame while device 0 finishes this one (one frame of latency)")


def device_list(args: argparse.Namespace) -> list[int] | None:
    """``--devices 0,1`` as indices (run), None when not given."""
    text = getattr(args, "devices", None)
    if text is None:
        return None
    try:
        out = [int(x) for x in str(text).split(",") if x.strip()]
    except ValueError:
        raise RGraphError.in_file(COMMAND_LINE, f"--devices expects device indices like 0,1, got '{text}'") from None
    if not out or min(out) < 0:
        raise RGraphError.in_file(COMMAND_LINE, f"--devices expects device indices like 0,1, got '{text}'")
    return out


def split_from_args(args: argparse.Namespace, *, indices: bool = False) -> Any:
    """The ``Split`` the arguments ask for, or None for a one-device plan."""
    from rgraph.compiler.multi_device import Split

    text = getattr(args, "devices", None)
    mode = getattr(args, "split", None)
    if text is None and mode is None:
        return None
    if indices:
        devices = len(device_list(args) or [0])
    else:
        try:
            devices = int(text) if text is not None else 1
        except ValueError:
            raise RGraphError.in_file(COMMAND_LINE, f"--devices expects a count, got '{text}'") from None
    if devices > 1 and mode is None:
        raise RGraphError.in_file(COMMAND_LINE, "--devices with more than one device needs --split sort-first|sort-last")
    if devices <= 1:
        return None
    return Split(devices, mode, getattr(args, "balance", "static") or "static")
