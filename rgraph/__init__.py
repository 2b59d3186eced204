"""rgraph: a declarative render-graph compiler for Vulkan."""

from __future__ import annotations

from importlib import import_module
from typing import Any

__version__ = "0.1.0"

#: Public names, imported on first use (``import rgraph`` stays cheap and Vulkan-free):
#: name -> "module:attribute".
_LAZY = {
    "load": "rgraph.compiled:load",
    "compile": "rgraph.compiled:compile",
    "Compiled": "rgraph.compiled:Compiled",
    "MemoryAnalysis": "rgraph.compiled:MemoryAnalysis",
    "Plan": "rgraph.plan.model:Plan",
    "load_plan": "rgraph.plan.read:load",
    "RGraphError": "rgraph.errors:RGraphError",
    "open_device": "rgraph.api:open_device",
    "Gpu": "rgraph.api:Gpu",
    "Executable": "rgraph.api:Executable",
}


def __getattr__(name: str) -> Any:
    target = _LAZY.get(name)
    if target is None:
        raise AttributeError(f"module 'rgraph' has no attribute {name!r}")
    module, _, attr = target.partition(":")
    return getattr(import_module(module), attr)


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
