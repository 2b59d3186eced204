"""Which compiled accelerators (``rgraph/**/*.pyx``, built by setup.py) are in use.

An accelerator mirrors a pure-Python function exactly: same inputs, same results, same
operation counts; only the time differs. ``RGRAPH_NATIVE=0`` in the environment makes every
caller use the pure-Python code (the tests compare the two). A build older than its ``.pyx``
(a checkout that changed the source since the last ``make setup``) is not used: the Python
code runs instead, with a warning to rebuild."""

from __future__ import annotations

import importlib
import importlib.util
import os
import warnings
from pathlib import Path
from types import ModuleType


def enabled() -> bool:
    """False when ``RGRAPH_NATIVE=0`` asks for the pure-Python code everywhere."""
    return os.environ.get("RGRAPH_NATIVE", "1") != "0"


def load(name: str) -> ModuleType | None:
    """The compiled module ``name`` (e.g. ``rgraph.memory._dive``), or None where it was not
    built or ``RGRAPH_NATIVE=0``."""
    if not enabled():
        return None
    try:
        found = importlib.util.find_spec(name)
    except ImportError:
        return None
    if found is None or found.origin is None:
        return None
    if stale(Path(found.origin)):
        warnings.warn(f"{name}: the build is older than its .pyx; running the Python code "
                      "(rebuild: make setup)", RuntimeWarning, stacklevel=2)
        return None
    try:
        return importlib.import_module(name)
    except ImportError:
        return None


def stale(built: Path) -> bool:
    """Whether the extension ``built`` is older than its source beside it: ``_x.pyx``, or for a
    twin (``_x.pxd`` without a ``.pyx``: setup.py ``TWINS``) the module ``x.py`` it compiles."""
    stem = built.name.split(".", 1)[0]
    source = built.with_name(stem + ".pyx")
    if not source.exists() and built.with_name(stem + ".pxd").exists():
        source = built.with_name(stem.removeprefix("_") + ".py")
    try:
        return source.stat().st_mtime > built.stat().st_mtime
    except OSError:
        return False
