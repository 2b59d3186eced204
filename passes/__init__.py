"""Built-in pass implementations (installed as rgraph.passes).

Each module registers its classes with ``rgraph.impl.register``; ``load_all`` imports every
module of this package so the registry sees them.
"""

from __future__ import annotations

import importlib
import pkgutil


def load_all() -> None:
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if not info.name.startswith("_"):
            importlib.import_module(f"{__name__}.{info.name}")
