"""File names a graph (or plan) gives for other files: checked before the OS sees them.

FORMAT.md says includes and ``scene:`` are "relative to this file"; they must stay inside
the folder tree of the graph the user named, unless the user allows otherwise on the
command line (``--allow-include-outside``). A file never decides on its own to reach out.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

from rgraph.errors import Location, RGraphError, quote

NAME_MAX = 255
PATH_MAX = 4096

_ALLOW_OUTSIDE: ContextVar[bool] = ContextVar("rgraph_allow_outside", default=False)


@contextmanager
def allow_outside(allowed: bool = True) -> Iterator[None]:
    """Within the block, referenced files may lie outside the referring file's folder tree."""
    token = _ALLOW_OUTSIDE.set(allowed)
    try:
        yield
    finally:
        _ALLOW_OUTSIDE.reset(token)


def outside_allowed() -> bool:
    return _ALLOW_OUTSIDE.get()


def check_name(name: str, loc: Location, what: str) -> None:
    """Refuse names the OS would choke on: NUL bytes, over-long components or paths."""
    if "\x00" in name:
        raise RGraphError.at(loc, f"{what} name {quote(name)} contains a NUL byte")
    if not name.strip():
        raise RGraphError.at(loc, f"{what} name is empty")
    try:
        encoded = os.fsencode(name)
    except UnicodeError:
        raise RGraphError.at(loc, f"{what} name {quote(name)} cannot be encoded as a file name") from None
    if len(encoded) > PATH_MAX:
        raise RGraphError.at(loc, f"{what} name is {len(encoded):,} bytes long (the limit is {PATH_MAX})")
    longest = max(encoded.split(b"/"), key=len)
    if len(longest) > NAME_MAX:
        raise RGraphError.at(loc, f"{what} name has a component of {len(longest):,} bytes (the limit is {NAME_MAX})")


def referenced(base: Path, root: Path, name: str, loc: Location, what: str, owner: str = "graph") -> Path:
    """``base / name`` after :func:`check_name`, refused when it leaves ``root``'s folder tree
    (the bundled graphs and scenes are always allowed: they ship with rgraph)."""
    check_name(name, loc, what)
    path = base / name
    if outside_allowed():
        return path
    from rgraph.resources import graphs_dir

    try:
        resolved = path.resolve()
        inside = any(resolved.is_relative_to(top.resolve()) for top in (root, graphs_dir()))
    except (OSError, RuntimeError) as exc:
        raise RGraphError.at(loc, f"cannot resolve {what} {quote(name)}: {exc}") from None
    if not inside:
        raise RGraphError.at(
            loc, f"{what} {quote(name)} lies outside the {owner}'s folder {quote(str(root))} "
                 f"(pass --allow-include-outside to allow it)")
    return path


def check_plan_scene(plan: dict, plan_path: Path) -> None:
    """A plan's ``scene_source`` must lie inside the plan's folder tree or the bundled graphs
    (where ``rgraph compile`` of a bundled graph points it), unless outside files are allowed."""
    from rgraph.resources import graphs_dir

    source = plan.get("scene_source")
    if source is None:
        return
    loc = Location(str(plan_path))
    if not isinstance(source, str):
        raise RGraphError.at(loc, f"scene_source must be a file name or null, got {quote(source)}")
    check_name(source, loc, "scene_source")
    if outside_allowed():
        return
    try:
        resolved = Path(source).resolve()
        inside = any(resolved.is_relative_to(root.resolve()) for root in (plan_path.parent, graphs_dir()))
    except (OSError, RuntimeError) as exc:
        raise RGraphError.at(loc, f"cannot resolve scene_source {quote(source)}: {exc}") from None
    if not inside:
        raise RGraphError.at(loc, f"scene_source {quote(source)} lies outside the plan's folder "
                                  f"{quote(str(plan_path.parent))} and the bundled graphs "
                                  f"(pass --allow-include-outside to allow it)")
