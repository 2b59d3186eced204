"""Built-in pass implementations (installed as rgraph.passes).

Each module registers its classes with ``rgraph.impl.register``; ``load_all`` imports every
module of this package so the registry sees them.
"""

from __future__ import annotations

import importlib
import pkgutil


def load_all() -> dict[str, Exception]:
    """Import every module; returns the modules that failed (name -> exception) so that one
    broken module does not hide the others' implementations."""
    failed: dict[str, Exception] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if not info.name.startswith("_"):
            try:
                importlib.import_module(f"{__name__}.{info.name}")
            except Exception as exc:  # noqa: BLE001 -- reported by rgraph.impl.lookup
                failed[f"{__name__}.{info.name}"] = exc
    return failed
