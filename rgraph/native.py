"""Which compiled accelerators (``rgraph/**/*.pyx``, built by setup.py) are in use.

An accelerator mirrors a pure-Python function exactly: same inputs, same results, same
operation counts; only the time differs. ``RGRAPH_NATIVE=0`` in the environment makes every
caller use the pure-Python code (the tests compare the two)."""

from __future__ import annotations

import importlib
import os
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
        return importlib.import_module(name)
    except ImportError:
        return None
